# Sourced by scripts/_venv.sh and scripts/test-min: export NUMBA_CACHE_DIR as a cache directory per state of src/
# under the root given as $1 (older ones are pruned). Numba's cache keys an entry by its own file only: a change to a
# helper inlined from another file would leave a stale compiled kernel (false passes, or results of old code).
# Each environment keeps its own root, so two Numba versions never share (and overwrite) one index file.
_NUMBA_CACHE_ROOT="$1"
SRC_HASH="$(cd "$ROOT" && find src -name '*.py' -type f -print0 | LC_ALL=C sort -z | xargs -0 sha256sum | sha256sum | cut -c1-16)"
mkdir -p "$_NUMBA_CACHE_ROOT/$SRC_HASH"
find "$_NUMBA_CACHE_ROOT" -mindepth 1 -maxdepth 1 -type d ! -name "$SRC_HASH" -exec rm -rf {} +
export NUMBA_CACHE_DIR="$_NUMBA_CACHE_ROOT/$SRC_HASH"
