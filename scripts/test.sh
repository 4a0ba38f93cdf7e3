#!/usr/bin/env bash
# The whole test suite, on a machine that has Rust (cargo) and Python 3 and nothing else.
#
#   bash scripts/test.sh
#
# 1. Provisions the Python packages the tests need, pinned: gmsh (meshes built on demand: the
#    L6/L7 ladder levels, the random scenes, the own-mesh example), vtk (the ParaView check) and
#    jsonschema (the schema check). They go into a virtual environment, target/test-venv
#    (STICKSLIP_TEST_VENV overrides the place), whose bin/ is put first on PATH so that the
#    tests' `python3` is that environment's; where Python cannot make one (no `venv` module),
#    into the user's site-packages with `pip install --user`.
# 2. Runs `cargo test --release --no-fail-fast` (every test target, even after a failure).
# 3. Runs two shipped cases and opens their .pvd/.vtu series with VTK's reader (ParaView's
#    pvpython where it is installed), and validates every shipped case against
#    `stickslip schema`.
# 4. Prints `tests: N passed, M failed` as its last line and exits non-zero if M > 0.
#
# Runs of the binary (here and in the tests) neither read nor fill the user's model cache:
# STICKSLIP_NO_CACHE=1 (tests/cache.rs uses its own temporary directories).
set -uo pipefail
cd "$(dirname "$0")/.."
export STICKSLIP_NO_CACHE=1

command -v cargo >/dev/null || { echo "scripts/test.sh: cargo is required (Rust stable, https://rustup.rs)"; exit 1; }
command -v python3 >/dev/null || { echo "scripts/test.sh: python3 is required"; exit 1; }

PACKAGES=("gmsh==4.15.2" "vtk==9.7.2" "jsonschema==4.26.0")
target="${CARGO_TARGET_DIR:-target}"
venv="${STICKSLIP_TEST_VENV:-$target/test-venv}"

provision() {
    if [ -x "$venv/bin/python3" ] || python3 -m venv "$venv" >/dev/null 2>&1; then
        "$venv/bin/python3" -m pip install --quiet --disable-pip-version-check "${PACKAGES[@]}" || return 1
        export PATH="$(cd "$venv/bin" && pwd):$PATH"
        echo "scripts/test.sh: Python packages in $venv: ${PACKAGES[*]}"
    else
        rm -rf "$venv"
        echo "scripts/test.sh: python3 -m venv is not available; installing with pip --user"
        python3 -m pip install --quiet --user --disable-pip-version-check "${PACKAGES[@]}" || return 1
    fi
    python3 -c "import gmsh, vtk, jsonschema" || return 1
}
if ! provision; then
    echo "scripts/test.sh: could not install ${PACKAGES[*]} (see the messages above)."
    echo "  Python's venv module may be missing (Debian/Ubuntu: apt-get install python3-venv), or"
    echo "  the package index unreachable; STICKSLIP_TEST_VENV=DIR puts the environment elsewhere."
    echo "tests: 0 passed, 1 failed"
    exit 1
fi

log=$(mktemp)
trap 'rm -f "$log"' EXIT

cargo test --release --no-fail-fast 2>&1 | tee "$log"
cargo_status=${PIPESTATUS[0]}

passed=$(grep -E '^test result:' "$log" | awk '{s += $4} END {print s + 0}')
failed=$(grep -E '^test result:' "$log" | awk '{s += $6} END {print s + 0}')
# A target that did not build, or died before its summary line, has no `test result:` line.
if [ "$cargo_status" -ne 0 ] && [ "$failed" -eq 0 ]; then
    echo "scripts/test.sh: cargo test exited with status $cargo_status"
    failed=$((failed + 1))
fi

bin="$target/release/stickslip"
check="$target/paraview-check"

# ParaView check: every documented array is in the .pvd/.vtu output of two shipped cases.
rm -rf "$check"
if "$bin" run cases/hertz.json --out "$check/hertz" --quiet &&
    "$bin" run cases/vm272_cm.json --out "$check/vm272_cm" --quiet &&
    python3 tests/paraview_check.py "$check/hertz" "$check/vm272_cm"; then
    passed=$((passed + 1))
else
    echo "scripts/test.sh: the ParaView check failed"
    failed=$((failed + 1))
fi

# Schema check: the shipped cases validate against `stickslip schema`, which rejects bad ones.
if python3 tests/schema_check.py "$bin"; then
    passed=$((passed + 1))
else
    echo "scripts/test.sh: the schema check failed"
    failed=$((failed + 1))
fi

echo "tests: $passed passed, $failed failed"
[ "$failed" -eq 0 ]
