"""Smoke test of an installed shipgym (``make dist-check`` runs it in a fresh venv per Python).

Run it with the venv's Python from outside the repository (``python -P tools/smoke.py`` or a
copy), so that ``import shipgym`` finds the installed wheel, not the source tree; it checks
that it does. Then:

- every registered ``shipgym/`` id: ``gym.make(id)``, ``reset(seed=0)``, 5 steps of a sampled
  action; an id that needs ``vessel=`` (the vessel-neutral tasks have no default vessel) runs
  once with every packaged vessel that fits the task (the harbour task in open water for a
  vessel larger than the harbour world); every id's batched form
  (``gym.make_vec(id, num_envs=2)``, same vessel rule) resets and steps once;
- the compiled laws went into Numba's on-disk cache (the per-user folder shipgym picks);
- the console script: ``shipgym --version`` (the installed version), ``shipgym list``,
  ``shipgym run harbour --no-progress`` (the whole harbour manoeuvre, a few seconds), each
  with exit code 0.

Prints one line per check and a summary; exits 1 on any failure (every check runs).
"""

from __future__ import annotations

import os
import subprocess
import sys
import time
import traceback
from collections.abc import Callable
from importlib import metadata
from pathlib import Path

RESULTS: list[tuple[str, bool, float]] = []


def check(name: str, fn: Callable[[], str | None]) -> None:
    """Run one check, print ``OK``/``FAIL`` with its time, and record it."""
    t0 = time.perf_counter()
    try:
        note = fn()
        ok = True
    except Exception:  # noqa: BLE001 - every failure is reported, then the next check runs
        note = traceback.format_exc(limit=4).rstrip().replace("\n", "\n      ")
        ok = False
    dt = time.perf_counter() - t0
    RESULTS.append((name, ok, dt))
    print(
        f"  {'OK  ' if ok else 'FAIL'} {name} ({dt:.1f} s){': ' + note if note else ''}", flush=True
    )


def _inside(path: Path, folder: Path) -> bool:
    try:
        path.resolve().relative_to(folder.resolve())
    except ValueError:
        return False
    return True


def main() -> int:
    t_start = time.perf_counter()
    print(f"shipgym smoke test: Python {sys.version.split()[0]} at {sys.executable}", flush=True)

    t0 = time.perf_counter()
    import gymnasium as gym

    import shipgym
    from shipgym.envs.registration import task_fits_vessel
    from shipgym.envs.scene import fits as scene_fits

    print(
        f"  import shipgym {shipgym.__version__} ({time.perf_counter() - t0:.1f} s): "
        f"{Path(shipgym.__file__).parent}",
        flush=True,
    )

    def installed() -> str:
        # the wheel in this venv, not a source tree on sys.path
        where = Path(shipgym.__file__)
        assert _inside(where, Path(sys.prefix)), f"{where} is not inside {sys.prefix}"
        assert shipgym.__version__ == metadata.version("shipgym"), shipgym.__version__
        from importlib.resources import files

        assets = Path(str(files("shipgym.assets")))
        assert _inside(assets, Path(sys.prefix)), assets
        n = sum(
            1
            for p in assets.rglob("*")
            if p.is_file() and p.suffix != ".py" and "__pycache__" not in p.parts
        )
        return f"version {shipgym.__version__}, {n} asset files in {assets}"

    check("import from the installed wheel", installed)

    vessels = shipgym.vessels()
    check("vessels() loads every packaged vessel", lambda: f"{len(vessels)}: {', '.join(vessels)}")

    def episode(env_id: str, **kwargs: object) -> Callable[[], str | None]:
        def run() -> str | None:
            env = gym.make(env_id, **kwargs)
            try:
                env.reset(seed=0)
                env.action_space.seed(0)
                for _ in range(5):
                    env.step(env.action_space.sample())
            finally:
                env.close()
            return None

        return run

    def batched(env_id: str, **kwargs: object) -> Callable[[], str | None]:
        def run() -> str | None:
            envs = gym.make_vec(env_id, num_envs=2, **kwargs)
            try:
                envs.reset(seed=0)
                envs.action_space.seed(0)
                envs.step(envs.action_space.sample())
            finally:
                envs.close()
            return None

        return run

    ids = sorted(i for i in gym.registry if i.startswith("shipgym/"))
    assert ids, "no shipgym/ ids registered"
    print(f"  {len(ids)} registered ids", flush=True)
    for env_id in ids:
        try:
            gym.make(env_id).close()
            needs_vessel = False
        except TypeError as exc:
            if "needs vessel=" not in str(exc):
                raise
            needs_vessel = True
        if not needs_vessel:
            check(env_id, episode(env_id))
            check(f"{env_id} make_vec(2)", batched(env_id))
            continue
        fits = [name for name, v in vessels.items() if task_fits_vessel(env_id, v)]
        print(f"  {env_id} needs vessel=: each that fits ({', '.join(fits)})", flush=True)
        if not fits:
            RESULTS.append((f"{env_id}: no packaged vessel fits", False, 0.0))
            print(f"  FAIL {env_id}: no packaged vessel fits", flush=True)
            continue
        for name in fits:
            # a vessel larger than the harbour world sails the harbour task in open water
            # (the env says so: "use the open-water scene")
            if env_id == "shipgym/Harbour-v0" and not scene_fits(vessels[name], "harbour"):
                check(
                    f"{env_id} vessel={name} scene=open-water",
                    episode(env_id, vessel=name, scene="open-water"),
                )
            else:
                check(f"{env_id} vessel={name}", episode(env_id, vessel=name))
        check(f"{env_id} make_vec(2) vessel={fits[0]}", batched(env_id, vessel=fits[0]))

    def numba_cache() -> str:
        import numba

        from shipgym import _jit

        if not _jit._CACHE:
            raise AssertionError("shipgym compiles in memory only (no private cache folder)")
        folder = Path(os.environ.get("NUMBA_CACHE_DIR") or numba.config.CACHE_DIR)
        index = list(folder.rglob("*.nbi"))
        assert index, f"no Numba cache index in {folder}"
        return f"{len(index)} cached functions in {folder}"

    check("Numba on-disk cache written", numba_cache)

    script = Path(sys.executable).with_name("shipgym")

    def cli(*args: str, expect: str | None = None) -> Callable[[], str | None]:
        def run() -> str | None:
            proc = subprocess.run([str(script), *args], capture_output=True, text=True, timeout=600)
            if proc.returncode != 0:
                raise AssertionError(
                    f"exit code {proc.returncode}\n{proc.stdout[-2000:]}\n{proc.stderr[-2000:]}"
                )
            if expect is not None:
                assert expect in proc.stdout, f"{expect!r} not in the output: {proc.stdout!r}"
            lines = proc.stdout.strip().splitlines()
            return f"{len(lines)} lines of output" if len(lines) > 1 else (lines or [""])[0]

        return run

    check("shipgym --version", cli("--version", expect=shipgym.__version__))
    check("shipgym list", cli("list", expect="shipgym/Harbour-v0"))
    check("shipgym run harbour --no-progress", cli("run", "harbour", "--no-progress"))

    failed = [name for name, ok, _ in RESULTS if not ok]
    total = time.perf_counter() - t_start
    print(
        f"smoke test, Python {sys.version.split()[0]}: {len(RESULTS) - len(failed)} of "
        f"{len(RESULTS)} checks passed in {total:.0f} s",
        flush=True,
    )
    for name in failed:
        print(f"  failed: {name}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
