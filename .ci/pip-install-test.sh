#!/usr/bin/env bash
# End-to-end test of the Python package as a user installs it: a fresh clone of
# this repository, `pip install ./bindings/python` into a new virtual environment
# (pip fetches the build backend, setuptools-rust, and numpy from PyPI; cargo
# builds libsddpm into the package), then `import sddpm` meshes a test part with
# no variable set, outside the clone.
#
# The clone reuses this tree's cargo build through CARGO_TARGET_DIR, and its files
# get the modification times of this tree's, so that cargo finds the library it
# built from them up to date: with target/ holding `cargo build --release`, nothing
# is compiled. Run from .ci/test-all.sh; prints how long the pip install took.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
target=${CARGO_TARGET_DIR:-$root/target}
python=python3
[ -x /usr/bin/python3 ] && python=/usr/bin/python3
work=$(mktemp -d "${TMPDIR:-/tmp}/sddpm-pip.XXXXXX")
trap 'rm -rf "$work"' EXIT

git clone -q "$root" "$work/sddpm"
"$python" - "$root" "$work/sddpm" <<'PY'
import os, subprocess, sys
src, dst = sys.argv[1:]
files = subprocess.run(["git", "ls-files", "-z"], cwd=dst, check=True, capture_output=True).stdout.split(b"\0")
for f in filter(None, files):
    s = os.path.join(src.encode(), f)
    if os.path.isfile(s):
        st = os.stat(s)
        os.utime(os.path.join(dst.encode(), f), ns=(st.st_atime_ns, st.st_mtime_ns))
PY

"$python" -m venv "$work/venv"
t0=$EPOCHREALTIME
CARGO_TARGET_DIR="$target" "$work/venv/bin/python" -m pip install --quiet --disable-pip-version-check "$work/sddpm/bindings/python"
t1=$EPOCHREALTIME
awk -v a="$t0" -v b="$t1" 'BEGIN { printf "pip install ./bindings/python: %.1f s\n", b - a }'

cd "$work"
env -u SDDPM_LIBRARY -u CARGO_TARGET_DIR -u PYTHONPATH "$work/venv/bin/python" - "$work/sddpm/tests/data/meshes/cgal_hole.off" "$work/out" <<'PY'
import os, sys
import sddpm

mesh, out = sys.argv[1:]
lib = sddpm.library_path()
assert lib.startswith(os.path.dirname(sddpm.__file__)), f"not the bundled library: {lib}"
r = sddpm.run(mesh, out, labels="THC+Z,0,0,0,0,0,0,0,0,0,0,0", steps=10, level=1)
for f in ["hex.vtu", "hex.k", "spline.bext", "model.k", "report.json", "report.html"]:
    assert os.path.isfile(os.path.join(out, f)), f
assert r["hex"]["inverted"] == 0, r["hex"]
print(f"import sddpm: {os.path.basename(lib)} (bundled), sddpm.run: {r['hex']['elements']} hex elements, "
      f"min scaled Jacobian {r['hex']['min_scaled_jacobian']:.3f}, {r['spline']['basis_functions']} basis functions")
PY
echo "pip install test: OK"
