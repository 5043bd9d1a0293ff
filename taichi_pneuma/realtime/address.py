"""Where the live page is served: the host checked before anything is built (it resolves, and this machine can
listen on each of its addresses), the port asked for (one free for IPv4 and IPv6 alike on every address), and the
page's URL as a browser on this machine opens it (wildcards named by a loopback address, IPv6 in brackets).
"""

from __future__ import annotations

import errno
import socket
from urllib.parse import quote

from ..errors import PneumaInputError, quoted


def url_host(host: str) -> str:
    """The host as a URL names it: 127.0.0.1 for the loopback names and every IPv4 address (''/0.0.0.0: this
    machine's browser reaches it there), [::1] for every IPv6 address ('::'), an IPv6 address in brackets."""
    if host in ("", "0.0.0.0", "localhost"):
        return "127.0.0.1"
    if host == "::":
        return "[::1]"
    return f"[{host}]" if ":" in host else host


def page_url(host: str, port: int, token: str) -> str:
    """The page's address: viser's client, told to open its websocket at the same address with the token."""
    where = f"{url_host(host)}:{port}"
    socket = f"ws://{where}/?token={token}"
    return f"http://{where}/?websocket={quote(socket, safe=':/[]')}"


def check_host(host: str) -> None:
    """Refuse a host that does not resolve, or whose addresses this machine cannot listen on (each bound to a
    free port and let go), naming it; '' is every address, as for the server."""
    try:
        addresses = socket.getaddrinfo(host or None, 0, type=socket.SOCK_STREAM, flags=socket.AI_PASSIVE)
    except (socket.gaierror, UnicodeError) as exc:
        raise PneumaInputError(
            f"host {quoted(host)} does not resolve ({exc}); give an address of this machine"
        ) from None
    for family, kind, proto, _, address in addresses:
        with socket.socket(family, kind, proto) as probe:
            try:
                probe.bind(address)
            except OSError as exc:
                raise PneumaInputError(
                    f"host {quoted(host)} ({address[0]}) is not an address this machine can listen on "
                    f"({exc.strerror}); give one of its own, e.g. 127.0.0.1"
                ) from None


def common_port(host: str, port: int) -> int:
    """The port to ask for: port, but for port 0 on every address (host ''), one free for IPv4 and IPv6 alike
    (asked for 0, the OS gives each its own, and the URL names one); 0 where this machine has no IPv6."""
    if port != 0 or host != "":
        return port
    for _ in range(100):
        with socket.socket(socket.AF_INET) as v4:
            v4.bind(("", 0))
            candidate = v4.getsockname()[1]
            try:
                with socket.socket(socket.AF_INET6) as v6:
                    v6.setsockopt(socket.IPPROTO_IPV6, socket.IPV6_V6ONLY, 1)
                    v6.bind(("::", candidate))
                    return candidate
            except OSError as exc:
                if exc.errno != errno.EADDRINUSE:  # no IPv6 here: IPv4 alone
                    return 0
    return 0
