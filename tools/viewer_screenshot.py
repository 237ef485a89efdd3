"""Open a recording the headless way (rerun's web viewer, headless Chromium); screenshot it.

The route ``shipgym run --record`` prints without a display (:func:`shipgym.viz.viewer_hint`),
run end to end: record a short run (``shipgym run harbour``; or take a given ``.rrd``), serve it
with ``rerun --serve-web --bind 127.0.0.1`` on two free ports, wait until the web viewer
answers, open the address (:func:`shipgym.viz.web_viewer_url`) in headless Chromium, wait until
the recording is shown (not rerun's Welcome page), save a PNG screenshot and stop everything
(also on Ctrl-C or SIGTERM).

    python tools/viewer_screenshot.py [RUN.rrd] [--out viewer.png] [--timeout 180]

Needs Chromium: Debian's package ``chromium`` (``apt-get install -y chromium``; 156.0.8078.129
when this was written), or ``--chromium PATH``. Chromium is driven over the DevTools protocol
on a pipe (``--remote-debugging-pipe``: NUL-separated JSON on file descriptors 3 and 4), so
neither a websocket client nor any other package is needed (Pillow, matplotlib's dependency,
reads the screenshots). Flags: ``--headless``, and ``--no-sandbox`` when running as root
(Chromium refuses to start otherwise). Without a GPU the viewer renders with SwiftShader,
Chromium's software Vulkan/WebGL ("Software rasterizer" in the viewer's top bar): Chromium 156
falls back to it by itself, and ``--use-angle=swiftshader --enable-unsafe-swiftshader`` ask for
it explicitly, for the versions that no longer do. ``--screenshot`` with
``--virtual-time-budget`` does not suffice: the viewer's WebAssembly loads in real time, so
that screenshot shows "Loading Application Bundle...".

"The recording is shown" is decided from pixels: the map's background colour (the recorder's
blueprint, :data:`MAP_BACKGROUND`) covers part of the window; rerun's Welcome and loading
pages have none of it. The screenshot kept is the first of two polls in a row that give the
same picture (the recording has finished streaming in), or the last after ``--settle`` seconds.
About 30 s in all on two cores (recording 3 s, the map shown 6-12 s after the page opens).

Exit status: 0 when the recording was shown (the screenshot is written either way, if the page
got that far), 1 when it was not within ``--timeout``, 2 when something could not start.
"""

from __future__ import annotations

import argparse
import base64
import contextlib
import fcntl
import io
import json
import os
import select
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
import urllib.error
import urllib.request
from collections.abc import Iterator
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from shipgym.viz.viewer import serve_web_command, web_viewer_url  # noqa: E402

#: the map view's background in the recorder's blueprint (shipgym/viz/recorder.py)
MAP_BACKGROUND = (12, 40, 64)
#: share of the window in that colour above which the recording counts as shown
MIN_MAP_SHARE = 0.02
WINDOW = (1600, 900)
#: flags for headless Chromium without a GPU (see the module docstring)
CHROMIUM_FLAGS = (
    "--headless",
    "--use-angle=swiftshader",
    "--enable-unsafe-swiftshader",
    "--no-first-run",
    "--no-default-browser-check",
    "--disable-extensions",
    "--disable-background-networking",
    "--hide-scrollbars",
    "--mute-audio",
)
CHROMIUM_NAMES = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")


class Failed(Exception):
    """Something could not start (exit status 2)."""


def _free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _rerun_executable() -> str:
    exe = shutil.which("rerun")
    if exe is None:
        cand = Path(sys.executable).parent / "rerun"
        exe = str(cand) if cand.exists() else None
    if exe is None:
        raise Failed("the rerun executable was not found (pip install rerun-sdk)")
    return exe


def _chromium_executable(given: str | None) -> str:
    if given:
        exe = shutil.which(given)
        if exe is None:
            raise Failed(f"no Chromium at {given}")
        return exe
    for name in CHROMIUM_NAMES:
        exe = shutil.which(name)
        if exe:
            return exe
    raise Failed("Chromium was not found on the PATH (Debian: apt-get install -y chromium)")


class Processes:
    """The child processes, each in a session of its own so that its whole group (Chromium's
    renderer and GPU processes included) is stopped by :meth:`stop_all`."""

    def __init__(self) -> None:
        self.procs: list[subprocess.Popen[bytes]] = []

    def start(self, args: list[str], **kw: Any) -> subprocess.Popen[bytes]:
        proc = subprocess.Popen(args, start_new_session=True, **kw)  # noqa: S603
        self.procs.append(proc)
        return proc

    def stop_all(self) -> None:
        for proc in reversed(self.procs):
            if proc.poll() is None:
                with contextlib.suppress(ProcessLookupError, PermissionError):
                    os.killpg(proc.pid, signal.SIGTERM)
        deadline = time.monotonic() + 5.0
        for proc in reversed(self.procs):
            try:
                proc.wait(timeout=max(0.1, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                with contextlib.suppress(ProcessLookupError, PermissionError):
                    os.killpg(proc.pid, signal.SIGKILL)
                proc.wait()
            # whatever is left of the group (a child that outlived its parent)
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.killpg(proc.pid, signal.SIGKILL)


@contextlib.contextmanager
def _signals_as_interrupt() -> Iterator[None]:
    """SIGTERM and SIGHUP raise KeyboardInterrupt, like Ctrl-C, so the clean-up runs."""

    def handler(signum: int, frame: Any) -> None:
        raise KeyboardInterrupt(signal.Signals(signum).name)

    old = {s: signal.signal(s, handler) for s in (signal.SIGTERM, signal.SIGHUP)}
    try:
        yield
    finally:
        for s, h in old.items():
            signal.signal(s, h)


def _above_9(fd: int) -> int:
    """The file descriptor moved to a number above 9 (close-on-exec)."""
    high = fcntl.fcntl(fd, fcntl.F_DUPFD_CLOEXEC, 10)
    os.close(fd)
    return high


class DevTools:
    """A minimal Chrome DevTools protocol client over ``--remote-debugging-pipe``."""

    def __init__(self, procs: Processes, args: list[str], log: Any) -> None:
        to_chrome_r, to_chrome_w = os.pipe()
        from_chrome_r, from_chrome_w = os.pipe()
        # Chromium's ends above fd 9, so that making them fds 3 and 4 overwrites neither
        to_chrome_r, from_chrome_w = _above_9(to_chrome_r), _above_9(from_chrome_w)

        def child() -> None:  # Chromium reads commands on fd 3 and answers on fd 4
            os.dup2(to_chrome_r, 3)
            os.dup2(from_chrome_w, 4)

        try:
            self.proc = procs.start(
                [*args, "--remote-debugging-pipe"],
                pass_fds=(3, 4),
                preexec_fn=child,  # noqa: PLW1509 - only dup2, before exec
                stdin=subprocess.DEVNULL,
                stdout=log,
                stderr=log,
            )
        finally:
            os.close(to_chrome_r)
            os.close(from_chrome_w)
        self.out = os.fdopen(to_chrome_w, "wb", buffering=0)
        self.inp = os.fdopen(from_chrome_r, "rb", buffering=0)
        self.buffer = b""
        self.next_id = 0
        self.session: str | None = None

    def close(self) -> None:
        for f in (self.out, self.inp):
            with contextlib.suppress(OSError):
                f.close()

    def call(self, method: str, timeout: float = 60.0, **params: Any) -> dict[str, Any]:
        self.next_id += 1
        msg: dict[str, Any] = {"id": self.next_id, "method": method, "params": params}
        if self.session is not None and not method.startswith("Target."):
            msg["sessionId"] = self.session
        self.out.write(json.dumps(msg).encode() + b"\0")
        deadline = time.monotonic() + timeout
        while True:
            while b"\0" not in self.buffer:
                left = deadline - time.monotonic()
                if left <= 0:
                    raise Failed(f"Chromium did not answer {method} in {timeout:.0f} s")
                ready, _, _ = select.select([self.inp], [], [], min(left, 1.0))
                if ready:
                    chunk = self.inp.read(1 << 20)
                    if not chunk:
                        raise Failed(f"Chromium exited (status {self.proc.wait()})")
                    self.buffer += chunk
            raw, self.buffer = self.buffer.split(b"\0", 1)
            answer = json.loads(raw)
            if answer.get("id") == self.next_id:
                if "error" in answer:
                    raise Failed(f"{method}: {answer['error'].get('message', answer['error'])}")
                return dict(answer.get("result", {}))

    def open_page(self, width: int, height: int) -> None:
        target = self.call("Target.createTarget", url="about:blank")["targetId"]
        self.session = self.call("Target.attachToTarget", targetId=target, flatten=True)[
            "sessionId"
        ]
        self.call(
            "Emulation.setDeviceMetricsOverride",
            width=width,
            height=height,
            deviceScaleFactor=1,
            mobile=False,
        )

    def evaluate(self, expression: str) -> Any:
        res = self.call("Runtime.evaluate", expression=expression, returnByValue=True)
        return res.get("result", {}).get("value")

    def screenshot(self) -> bytes:
        data = self.call("Page.captureScreenshot", format="png", timeout=90.0)["data"]
        return base64.b64decode(data)


def map_share(png: bytes, colour: tuple[int, int, int] = MAP_BACKGROUND, tol: int = 6) -> float:
    """The share of the picture's pixels within ``tol`` of ``colour`` (each channel)."""
    import numpy as np
    from PIL import Image  # matplotlib's dependency: installed with shipgym

    with Image.open(io.BytesIO(png)) as img:
        rgb = np.asarray(img.convert("RGB"), dtype=np.int16)
    near = np.all(np.abs(rgb - np.asarray(colour, dtype=np.int16)) <= tol, axis=-1)
    return float(near.mean())


def _wait_for_server(web_port: int, grpc_port: int, rerun: subprocess.Popen[bytes],
                     timeout: float) -> float:  # fmt: skip
    t0 = time.monotonic()
    while True:
        if rerun.poll() is not None:
            raise Failed(f"rerun exited (status {rerun.returncode}) before serving")
        try:
            with urllib.request.urlopen(f"http://127.0.0.1:{web_port}/", timeout=2.0) as r:  # noqa: S310
                ok = r.status == 200
            with socket.create_connection(("127.0.0.1", grpc_port), timeout=2.0):
                pass
            if ok:
                return time.monotonic() - t0
        except (OSError, urllib.error.URLError):
            pass
        if time.monotonic() - t0 > timeout:
            raise Failed(f"rerun's web viewer did not answer on port {web_port} in {timeout:.0f} s")
        time.sleep(0.2)


def _record(work: Path, scenario: str, procs: Processes) -> Path:
    path = work / "run.rrd"
    cmd = [sys.executable, "-m", "shipgym.cli", "run", scenario, "--no-progress",
           "--record", str(path)]  # fmt: skip
    proc = procs.start(cmd, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    out, _ = proc.communicate()
    if proc.returncode != 0 or not path.is_file():
        raise Failed(f"shipgym run failed (status {proc.returncode}):\n{out.decode()[-2000:]}")
    return path


def _rerun_route_line(log_path: Path) -> str | None:
    """rerun's own "Hosting a web-viewer at ... connect at ..." line, if it logged one."""
    with contextlib.suppress(OSError):
        for line in log_path.read_text(errors="replace").splitlines():
            if "connect at" in line:
                return line[line.index("Hosting") if "Hosting" in line else 0 :].strip()
    return None


def _serve(rrd: Path, rerun_exe: str, work: Path, procs: Processes) -> tuple[int, int]:
    """Start ``rerun --serve-web`` on two free ports; wait until it answers; the ports."""
    web_port, grpc_port = _free_port(), _free_port()
    while grpc_port == web_port:
        grpc_port = _free_port()
    print(f"serving: {serve_web_command(rrd, web_port=web_port, grpc_port=grpc_port)}")
    rerun_log = work / "rerun.log"
    cmd = [rerun_exe, "--serve-web", "--bind", "127.0.0.1", "--web-viewer-port", str(web_port),
           "--port", str(grpc_port), str(rrd)]  # fmt: skip
    with open(rerun_log, "wb") as log:
        rerun = procs.start(cmd, stdin=subprocess.DEVNULL, stdout=log, stderr=log,
                            env={**os.environ, "NO_COLOR": "1"})  # fmt: skip
    waited = _wait_for_server(web_port, grpc_port, rerun, timeout=30.0)
    print(f"web viewer answering after {waited:.1f} s")
    line = _rerun_route_line(rerun_log)
    if line:
        print(f"rerun says: {line}")
    return web_port, grpc_port


class Seen:
    """What the browser showed: the last screenshot, when the map appeared, and so on."""

    png: bytes = b""
    share: float = 0.0
    shown_at: float | None = None
    stable: bool = False
    renderer: str = "?"
    webgpu: bool = False


def _browse(devtools: DevTools, url: str, args: argparse.Namespace) -> Seen:
    """Open ``url``; screenshot every ``args.poll`` s until the map shows (at most
    ``args.timeout`` s) and then until two screenshots are alike (at most ``args.settle`` s)."""
    seen = Seen()
    devtools.open_page(*WINDOW)
    t_nav = time.monotonic()
    devtools.call("Page.navigate", url=url)
    last = b""
    while True:
        time.sleep(args.poll)
        seen.png = devtools.screenshot()
        seen.share = map_share(seen.png)
        now = time.monotonic() - t_nav
        if seen.shown_at is None:
            if seen.share >= MIN_MAP_SHARE:
                seen.shown_at = now
                print(f"recording shown after {now:.1f} s (map {seen.share:.0%} of the window)")
            elif now > args.timeout:
                break
        elif seen.png == last:
            seen.stable = True
            break
        elif now - seen.shown_at > args.settle:
            break
        last = seen.png
    seen.renderer = str(devtools.evaluate(RENDERER_JS))
    seen.webgpu = bool(devtools.evaluate("!!navigator.gpu"))
    return seen


#: the WebGL2 renderer Chromium gives the page ("... SwiftShader ..." without a GPU)
RENDERER_JS = """(() => {
  const g = document.createElement('canvas').getContext('webgl2');
  if (!g) return 'no WebGL2';
  const d = g.getExtension('WEBGL_debug_renderer_info');
  return d ? g.getParameter(d.UNMASKED_RENDERER_WEBGL) : 'WebGL2';
})()"""


def run(args: argparse.Namespace) -> int:
    """Record (or take ``args.rrd``), serve, browse, screenshot; the exit status."""
    t_start = time.monotonic()
    chromium = _chromium_executable(args.chromium)
    rerun_exe = _rerun_executable()
    out = Path(args.out).resolve()
    out.parent.mkdir(parents=True, exist_ok=True)
    procs = Processes()
    work = Path(tempfile.mkdtemp(prefix="shipgym-viewer-"))
    devtools: DevTools | None = None
    try:
        with _signals_as_interrupt():
            if args.rrd is None:
                t0 = time.monotonic()
                rrd = _record(work, args.scenario, procs)
                print(f"recorded {args.scenario} to {rrd} in {time.monotonic() - t0:.1f} s")
            else:
                rrd = Path(args.rrd).resolve()
                if not rrd.is_file():
                    raise Failed(f"no recording at {rrd}")
            url = web_viewer_url(*_serve(rrd, rerun_exe, work, procs))
            print(f"opening {url}")
            flags = list(CHROMIUM_FLAGS)
            if hasattr(os, "geteuid") and os.geteuid() == 0:
                flags.append("--no-sandbox")  # Chromium's sandbox refuses to run as root
            w, h = WINDOW
            flags += [f"--window-size={w},{h}", f"--user-data-dir={work / 'profile'}"]
            with open(work / "chromium.log", "wb") as log:
                devtools = DevTools(procs, [chromium, *flags, "about:blank"], log)
            seen = _browse(devtools, url, args)
    except KeyboardInterrupt:
        print("interrupted; stopping rerun and Chromium", file=sys.stderr)
        return 130
    finally:
        if devtools is not None:
            devtools.close()
        procs.stop_all()
        shutil.rmtree(work, ignore_errors=True)
    if seen.png:
        out.write_bytes(seen.png)
    elapsed = time.monotonic() - t_start
    gpu = "present" if seen.webgpu else "absent"
    print(f"browser: {Path(chromium).name}, WebGL2 renderer {seen.renderer!r}, WebGPU API {gpu}")
    if seen.shown_at is None:
        print(f"NOT shown: after {args.timeout:.0f} s the page has no map (its colour on "
              f"{seen.share:.1%} of the window: rerun's Welcome or loading page); "
              f"screenshot {out}; {elapsed:.1f} s in all")  # fmt: skip
        return 1
    how = "settled (two polls alike)" if seen.stable else f"changing after {args.settle:.0f} s"
    print(f"saw the recording: map on {seen.share:.0%} of the window, {how}; "
          f"screenshot {out} ({w}x{h}); {elapsed:.1f} s in all")  # fmt: skip
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description="Open a recording in rerun's web viewer in headless Chromium and save a "
        "screenshot (the route shipgym prints without a display)."
    )
    parser.add_argument("rrd", nargs="?", help="a recording (default: record shipgym run SCENARIO)")
    parser.add_argument("--scenario", default="harbour", help="what to record (default: harbour)")
    parser.add_argument("--out", default="viewer.png", help="the PNG (default: viewer.png)")
    parser.add_argument("--chromium", default=None, help="the browser (default: chromium on PATH)")
    parser.add_argument(
        "--timeout", type=float, default=180.0, help="longest wait for the map to show (s)"
    )
    parser.add_argument(
        "--settle", type=float, default=60.0, help="then the longest wait for a still picture (s)"
    )
    parser.add_argument("--poll", type=float, default=2.0, help="seconds between screenshots")
    args = parser.parse_args(argv)
    if isinstance(sys.stdout, io.TextIOWrapper):
        sys.stdout.reconfigure(line_buffering=True)  # progress lines as they happen, piped too
    try:
        return run(args)
    except Failed as exc:
        print(f"viewer_screenshot: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
