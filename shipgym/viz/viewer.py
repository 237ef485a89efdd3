"""How to open a recording: the one place that says which rerun command to run.

Public names: ``GRPC_PORT``, ``WEB_VIEWER_PORT``, ``has_display``, ``serve_web_command``,
``viewer_hint``, ``web_viewer_url``.

With a display, ``rerun PATH`` opens the native viewer. Without one (Linux with neither
``DISPLAY`` nor ``WAYLAND_DISPLAY``), rerun's web viewer is the route: ``rerun --serve-web
--bind 127.0.0.1 PATH`` serves the viewer over HTTP (:data:`WEB_VIEWER_PORT`) and the recording
over gRPC (:data:`GRPC_PORT`), on this machine only; the browser must open the address that
names the gRPC server in its ``url`` parameter (:func:`web_viewer_url`): the bare
``http://127.0.0.1:9090`` shows rerun's Welcome page, not the recording. From another machine
both ports are forwarded over SSH. ``tools/viewer_screenshot.py`` runs this route end to end in
headless Chromium. User guide: docs/tutorials/recording.md ("Look at it in a browser").

No rerun import here: the hint is plain text.
"""

from __future__ import annotations

import os
import shlex
import subprocess
import sys
from collections.abc import Mapping
from pathlib import Path
from urllib.parse import quote

__all__ = [
    "GRPC_PORT",
    "WEB_VIEWER_PORT",
    "has_display",
    "serve_web_command",
    "viewer_hint",
    "web_viewer_url",
]

#: rerun's defaults: the web viewer's HTTP port (``--web-viewer-port``) and the port of the
#: gRPC server that serves the recording to it (``--port``)
WEB_VIEWER_PORT = 9090
GRPC_PORT = 9876
#: the address both servers listen on, and the one the browser uses (``localhost`` may resolve
#: to ``::1`` first, where nothing listens)
HOST = "127.0.0.1"


def has_display(environ: Mapping[str, str] | None = None, platform: str | None = None) -> bool:
    """Whether a native viewer window can open: on Linux (and the other X11/Wayland systems) a
    non-empty ``DISPLAY`` or ``WAYLAND_DISPLAY``; macOS and Windows are assumed to have one."""
    env = os.environ if environ is None else environ
    plat = sys.platform if platform is None else platform
    if plat.startswith(("darwin", "win32", "cygwin")):
        return True
    return bool(env.get("DISPLAY") or env.get("WAYLAND_DISPLAY"))


def _quote(path: str | os.PathLike[str], platform: str | None = None) -> str:
    text = os.fspath(path)
    if (sys.platform if platform is None else platform).startswith("win32"):
        return subprocess.list2cmdline([text])
    return shlex.quote(text)


def web_viewer_url(web_port: int = WEB_VIEWER_PORT, grpc_port: int = GRPC_PORT) -> str:
    """The address that opens rerun's web viewer with the served recording loaded:
    ``http://127.0.0.1:9090/?url=rerun%2Bhttp%3A%2F%2F127.0.0.1%3A9876%2Fproxy``."""
    source = f"rerun+http://{HOST}:{int(grpc_port)}/proxy"
    return f"http://{HOST}:{int(web_port)}/?url={quote(source, safe='')}"


def serve_web_command(
    path: str | os.PathLike[str],
    web_port: int = WEB_VIEWER_PORT,
    grpc_port: int = GRPC_PORT,
    platform: str | None = None,
) -> str:
    """The shell command that serves ``path`` in rerun's web viewer on this machine only
    (the port options only where they differ from rerun's defaults)."""
    words = ["rerun", "--serve-web", "--bind", HOST]
    if int(web_port) != WEB_VIEWER_PORT:
        words += ["--web-viewer-port", str(int(web_port))]
    if int(grpc_port) != GRPC_PORT:
        words += ["--port", str(int(grpc_port))]
    return " ".join([*words, _quote(path, platform)])


def viewer_hint(
    path: str | os.PathLike[str],
    environ: Mapping[str, str] | None = None,
    platform: str | None = None,
) -> str:
    """What to run to look at the recording ``path`` (lines, no final newline).

    With a display: ``open the recording with: rerun PATH``. Without one: the
    ``rerun --serve-web`` command, the address to open in a browser and the SSH port forward
    for a browser on another machine, each on a line of its own, indented, to copy.
    ``environ`` and ``platform`` default to this process's (:func:`has_display`)."""
    p = Path(os.fspath(path))
    if has_display(environ, platform):
        return f"open the recording with: rerun {_quote(p, platform)}"
    forward = " ".join(f"-L {port}:{HOST}:{port}" for port in (WEB_VIEWER_PORT, GRPC_PORT))
    return "\n".join(
        [
            "open the recording with rerun's web viewer (no display here; it serves until Ctrl-C):",
            f"  {serve_web_command(p, platform=platform)}",
            "then open this address in a browser on this machine:",
            f"  {web_viewer_url()}",
            "or in a browser on another machine, once both ports are forwarded from it:",
            f"  ssh -N {forward} USER@HOST",
        ]
    )
