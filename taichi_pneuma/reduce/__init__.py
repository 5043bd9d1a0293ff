"""Reduced-order models of a scene's quasistatic equilibria: a POD basis V of its displacements (u = V q) and an
ECSW hyper-reduced elastic term (a few elements with weights), trained on equilibria of the full model.

    snapshots.py   equilibria of the full model over the scene's actuation space (its schedule and a Latin hypercube)
    pod.py         the basis: the leading left singular vectors of the snapshot matrix
    ecsw.py        element weights w >= 0 by non-negative least squares (Energy-Conserving Sampling and Weighting)
    model.py       the reduced energy, gradient V^T g and Hessian V^T H V
    solve.py       Newton on q with a backtracking line search; the error indicator
    store.py       the trained model as one .npz file, refused for another scene
    train.py       the whole training, and the validation against the full model
"""
