# Shared by scripts/run and scripts/test: create .venv (once) and install scalesynth into it.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VENV="${SCALESYNTH_VENV:-$ROOT/.venv}"
PY="${PYTHON:-python3}"
if [ ! -x "$VENV/bin/python" ]; then
  echo "[scalesynth] creating virtual environment in $VENV" >&2
  "$PY" -m venv "$VENV"
fi
EXTRA="${1:-}"
STAMP="$VENV/.installed$EXTRA"
if [ ! -f "$STAMP" ] || [ "$ROOT/pyproject.toml" -nt "$STAMP" ]; then
  echo "[scalesynth] installing scalesynth${EXTRA} (first run takes a minute)" >&2
  "$VENV/bin/python" -m pip install --quiet --upgrade pip >&2
  "$VENV/bin/python" -m pip install --quiet -e "$ROOT$EXTRA" >&2
  touch "$STAMP"
fi
export PATH="$VENV/bin:$PATH"
# scripts/test and scripts/run use a Numba cache directory per state of src/ (scripts/_numba_cache.sh)
source "$ROOT/scripts/_numba_cache.sh" "$ROOT/.numba-cache"
