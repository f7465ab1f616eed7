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
# Numba's cache keys an entry by its own file only: a change to a helper inlined from another file would leave a
# stale compiled kernel (false passes, or results of old code). scripts/test and scripts/run use a cache directory
# per state of src/ (older ones are pruned).
SRC_HASH="$(cd "$ROOT" && find src -name '*.py' -type f -print0 | LC_ALL=C sort -z | xargs -0 sha256sum | sha256sum | cut -c1-16)"
CACHE_ROOT="$ROOT/.numba-cache"
mkdir -p "$CACHE_ROOT/$SRC_HASH"
find "$CACHE_ROOT" -mindepth 1 -maxdepth 1 -type d ! -name "$SRC_HASH" -exec rm -rf {} +
export NUMBA_CACHE_DIR="$CACHE_ROOT/$SRC_HASH"
