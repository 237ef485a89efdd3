#!/usr/bin/env bash
# The built wheel in a fresh venv of each given Python, smoke-tested there (make dist-check).
#   usage: tools/dist_check.sh WHEEL PYTHON...
#   e.g.   tools/dist_check.sh dist/shipgym-0.1.0-py3-none-any.whl python3.12 python3.13
# For each PYTHON (a command name such as python3.12, found on the PATH or as pyenv's
# ~/.pyenv/versions/3.12.*/bin/python): a venv in a temporary folder, the locked pip, then
# `pip install WHEEL -c requirements/lock.txt`: the package's dependencies from the package
# index within pyproject's ranges, at the versions of the lock (all of them install from
# wheels on CPython 3.11.7, 3.12.1 and 3.13.0: no source build). tools/smoke.py then runs with
# that venv's Python from the temporary folder (python -P: not the source tree, the installed
# wheel), with a Numba cache folder of its own (XDG_CACHE_HOME), so the compiled laws are
# compiled and cached afresh from the installed files. A PYTHON that is not found is skipped
# with a message, or is an error where CI is true. Prints each Python's install and smoke
# times and its venv's size.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
[[ $# -ge 2 ]] || { echo "usage: $0 WHEEL PYTHON..." >&2; exit 2; }
[[ -f $1 ]] || { echo "dist_check: no wheel $1 (run make dist)" >&2; exit 2; }
wheel=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
shift
lock=$root/requirements/lock.txt

# this machine's pip configuration adds package indexes that lack most names: hide its notices
quiet() { "$@" 2>&1 | { grep -v "^WARNING: Location '.*' is ignored" || true; }; }

# the interpreter of a command name: on the PATH (and working: a pyenv shim of a version that
# is not selected fails), else pyenv's newest install of that version; empty if none
find_python() {
    local name=$1 want=${1#python} cand
    for cand in "$(command -v "$name" || true)" \
        $(ls -d "${PYENV_ROOT:-$HOME/.pyenv}"/versions/"$want".*/bin/python 2>/dev/null | sort -V -r); do
        [[ -n $cand ]] || continue
        if "$cand" -c "import sys; sys.exit(f'{sys.version_info[0]}.{sys.version_info[1]}' != '$want')" \
            2>/dev/null; then
            "$cand" -c 'import sys; print(sys.executable)'
            return
        fi
    done
}

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
summary=()
failed=0
for name in "$@"; do
    py=$(find_python "$name")
    if [[ -z $py ]]; then
        if [[ ${CI:-} == true ]]; then
            echo "dist_check: error: $name not found (CI=true: every Python of the check is needed)" >&2
            summary+=("$name: NOT FOUND (error)")
            failed=1
        else
            echo "dist_check: $name not found: skipped (an error where CI=true)"
            summary+=("$name: not found, skipped")
        fi
        continue
    fi
    echo "== $name: $py ($("$py" -c 'import sys; print(sys.version.split()[0])'))"
    dir=$tmp/$name
    mkdir -p "$dir"
    t0=$SECONDS
    "$py" -m venv "$dir/venv"
    vpy=$dir/venv/bin/python
    if ! { quiet "$vpy" -m pip install --quiet "$(grep -m1 '^pip==' "$lock")" &&
        quiet "$vpy" -m pip install --quiet "$wheel" -c "$lock"; }; then
        echo "dist_check: $name: pip install of the wheel failed" >&2
        summary+=("$name: INSTALL FAILED")
        failed=1
        continue
    fi
    t1=$SECONDS
    # what pip installed beside the lock's versions (none expected: the lock holds every
    # dependency of the core, and -c pins each of them)
    "$vpy" - "$lock" <<'PY'
import re, sys
from importlib import metadata
canon = lambda n: re.sub(r"[-_.]+", "-", n).lower()
pins = dict(l.strip().split("==", 1) for l in open(sys.argv[1]) if "==" in l and l[0] != "#")
pins = {canon(k): v for k, v in pins.items()}
got = {canon(d.metadata["Name"]): d.version for d in metadata.distributions()}
extra = sorted(f"{n}=={v}" for n, v in got.items() if n not in pins and n != "shipgym")
other = sorted(f"{n}=={v}" for n, v in got.items() if n in pins and v.split("+")[0] != pins[n])
print(f"  installed {len(got)} distributions; not in the lock: {', '.join(extra) or 'none'}; "
      f"other than the lock: {', '.join(other) or 'none'}")
PY
    status=0
    (cd "$dir" && env -u PYTHONPATH -u NUMBA_CACHE_DIR XDG_CACHE_HOME="$dir/cache" \
        "$vpy" -P "$root/tools/smoke.py") || status=$?
    t2=$SECONDS
    size=$(du -sh "$dir/venv" | cut -f1)
    line="$name: install $((t1 - t0)) s, smoke $((t2 - t1)) s, venv $size"
    if [[ $status -ne 0 ]]; then
        summary+=("$line: SMOKE FAILED")
        failed=1
    else
        summary+=("$line: ok")
    fi
    rm -rf "$dir"
done
echo "== dist-check of $(basename "$wheel")"
printf '  %s\n' "${summary[@]}"
exit $failed
