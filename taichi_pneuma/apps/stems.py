"""The stem of a run's result files: the scene's name and what the run changed of it, so that a different run never
overwrites another's files and a re-run of the same one replaces only its own.
"""

from __future__ import annotations

import argparse

from .cli import BEAM_DEFAULTS
from .quality import QUALITY

MAX_SUFFIX = 40  # a readable stem suffix longer than this is replaced by the scene's hash


def quality_stem(args: argparse.Namespace) -> str:
    """The suffix a --quality other than the default adds to the result file names ('' or '_high', ...), so
    runs of one scene at two qualities do not overwrite each other."""
    return "" if args.quality == "default" else f"_{args.quality}"


def result_stem(base: str, args: argparse.Namespace, *scenes) -> str:
    """The stem of a run's result files: base (a scene's name, or the reference beam's 'inflate_cy+0.15'), then
    what the run changed of that scene, so that a different run never overwrites its files and a re-run of the
    same one replaces only its own: the reference-beam flags that differ from their defaults (without --scene:
    '_order2', '_E20000'; --max-area and --order against the --quality preset) and every --set as given
    ('_E2e4_nu0.49'), made a valid stem (output.reduce_to_stem); past MAX_SUFFIX characters instead '_' and the
    first 8 hex digits of scene_sha256 of the scenes as run; then quality_stem."""
    from ..io.output import reduce_to_stem
    from ..result import scene_sha256

    parts = []
    if not getattr(args, "scene", None):
        parts += [f"{k}{getattr(args, k):g}" for k, v in BEAM_DEFAULTS.items() if getattr(args, k) != v]
        preset_area, preset_order, _ = QUALITY[args.quality]
        parts += [f"max_area{args.max_area:g}"] if args.max_area != preset_area else []
        parts += [f"order{args.order}"] if args.order != preset_order else []
    for text in args.set:
        key, _, value = text.partition("=")
        parts.append(key.strip() + value.strip())
    suffix = reduce_to_stem("_".join(parts)) if parts else ""
    if len(suffix) > MAX_SUFFIX:
        suffix = scene_sha256(*scenes)[:8]
    return base + (f"_{suffix}" if suffix else "") + quality_stem(args)
