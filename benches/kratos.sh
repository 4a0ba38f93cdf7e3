#!/usr/bin/env bash
# Speed against accuracy, side by side with Kratos Multiphysics' mortar contact (issue 51).
# A bench, not a test: it is not part of `cargo test`.
#
#   benches/kratos.sh [bench.py options]        e.g. benches/kratos.sh --reps 3
#
# 1. makes out/bench/kratos-venv (python3 -m venv) and pip-installs the pinned Kratos wheels
#    (KratosMultiphysics, KratosStructuralMechanicsApplication,
#    KratosContactStructuralMechanicsApplication, KratosLinearSolversApplication 10.4.4),
#    gmsh (the linear-triangle meshes of meshes/vm272.geo), numpy and matplotlib into it;
#    a failed install stops the bench with the pip log's tail (nothing is skipped silently);
# 2. needs our release binary (target/release/stickslip; built with `cargo build --release`
#    if missing) and runs post/kratos/bench.py: both codes alternating on every case and
#    level, medians over the repetitions, out/bench/kratos.{csv,md};
# 3. draws docs/figs/speed_accuracy_3codes_{pressure,shear}.png with post/kratos/chart.py
#    (CalculiX from post/kratos/calculix_2026-11-26.csv, the documented accuracy-bench run).
#
# Environment: KRATOS_VENV (out/bench/kratos-venv), PYTHON (python3), STICKSLIP_BIN
# (target/release/stickslip), KRATOS_FIGS (docs/figs; "none" draws nothing).
set -euo pipefail
cd "$(dirname "$0")/.."
VENV=${KRATOS_VENV:-out/bench/kratos-venv}
PY=${PYTHON:-python3}
BIN=${STICKSLIP_BIN:-target/release/stickslip}
FIGS=${KRATOS_FIGS:-docs/figs}
PKGS=(KratosMultiphysics==10.4.4 KratosStructuralMechanicsApplication==10.4.4
      KratosContactStructuralMechanicsApplication==10.4.4 KratosLinearSolversApplication==10.4.4
      gmsh numpy matplotlib)

mkdir -p out/bench
if [ ! -x "$VENV/bin/python" ]; then
  echo "kratos bench: making $VENV" >&2
  "$PY" -m venv "$VENV"
fi
if ! "$VENV/bin/python" - <<'EOF' 2>/dev/null
import importlib.metadata as m, sys
want = {"KratosMultiphysics": "10.4.4", "KratosStructuralMechanicsApplication": "10.4.4",
        "KratosContactStructuralMechanicsApplication": "10.4.4", "KratosLinearSolversApplication": "10.4.4"}
sys.exit(0 if all(m.version(k) == v for k, v in want.items()) and all(
    m.version(k) for k in ("gmsh", "numpy", "matplotlib")) else 1)
EOF
then
  echo "kratos bench: pip install ${PKGS[*]} (log: out/bench/kratos-pip.log)" >&2
  if ! "$VENV/bin/pip" install "${PKGS[@]}" >out/bench/kratos-pip.log 2>&1; then
    echo "kratos bench: FAILED to install the Kratos packages; the bench did not run. Last lines of the log:" >&2
    tail -20 out/bench/kratos-pip.log >&2
    exit 2
  fi
fi
"$VENV/bin/python" -c "import KratosMultiphysics, KratosMultiphysics.StructuralMechanicsApplication, \
KratosMultiphysics.ContactStructuralMechanicsApplication, KratosMultiphysics.LinearSolversApplication, gmsh" \
  >/dev/null 2>&1 || { echo "kratos bench: the Kratos packages do not import; the bench did not run" >&2; exit 2; }

if [ ! -x "$BIN" ]; then
  echo "kratos bench: $BIN missing, building it (cargo build --release)" >&2
  cargo build --release
fi

"$VENV/bin/python" post/kratos/bench.py --bin "$BIN" "$@"
if [ "$FIGS" != none ]; then
  "$VENV/bin/python" post/kratos/chart.py out/bench/kratos.csv "$FIGS"
fi
