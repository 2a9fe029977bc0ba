#!/usr/bin/env bash
# Fails when a library file includes a module it may not depend on (lib/README.md, "Modules").
# Parses every `#include <incise/<module>/...>` under lib/include/incise/<m>/, lib/src/<m>/ and
# lib/cli/ and checks <module> against the table below, which is the module order drawn in
# lib/README.md. A module may include itself and the modules listed for it, nothing else.
# Usage: ci/check-module-order.sh [ROOT]   (ROOT defaults to the repository root)
set -euo pipefail
root=${1:-"$(dirname "$0")/.."}
cd "$root"

# module: the modules it may include (besides itself). Keep in step with lib/README.md.
declare -A allowed=(
  [core]=""
  [mesh]="core"
  [io]="core mesh"
  [material]="core"
  [fem]="core mesh material"
  [linalg]="core"
  [spectral]="core"
  [solver]="core linalg spectral"
  [cut]="core mesh"
  [needle]="core mesh material fem linalg solver"
  [delaunay]="core mesh"
  [fixtures]="core mesh io material fem linalg spectral solver"
  [interactive]="core mesh material fem linalg solver cut needle delaunay"
  [scene]="core mesh io material fem linalg spectral solver cut needle delaunay interactive"
  [certify]="core mesh io material fem linalg spectral solver cut needle delaunay fixtures interactive scene"
  [cli]="core mesh io material fem linalg spectral solver cut needle delaunay fixtures interactive scene certify"
)

bad=0
checked=0
check_file() {  # file module
  local file=$1 module=$2 line n=0 inc
  while IFS= read -r line; do
    n=$((n + 1))
    [[ $line =~ ^[[:space:]]*#[[:space:]]*include[[:space:]]*\<incise/([a-z_]+)/ ]] || continue
    inc=${BASH_REMATCH[1]}
    checked=$((checked + 1))
    if [ -z "${allowed[$inc]+x}" ]; then
      echo "$file:$n: includes <incise/$inc/...>, which is not a module of lib/README.md"
      bad=1
    elif [ "$inc" != "$module" ] && [[ " ${allowed[$module]} " != *" $inc "* ]]; then
      echo "$file:$n: module '$module' may not include <incise/$inc/...> (allowed: ${allowed[$module]:-none})"
      bad=1
    fi
  done <"$file"
}

for dir in lib/include/incise/* lib/src/*; do
  [ -d "$dir" ] || continue
  module=$(basename "$dir")
  if [ -z "${allowed[$module]+x}" ]; then
    echo "$dir: folder is not a module of lib/README.md (add it to ci/check-module-order.sh)"
    bad=1
    continue
  fi
  while IFS= read -r -d '' f; do check_file "$f" "$module"; done \
    < <(find "$dir" -type f \( -name '*.hpp' -o -name '*.cpp' \) -print0)
done
if [ -d lib/cli ]; then
  while IFS= read -r -d '' f; do check_file "$f" cli; done \
    < <(find lib/cli -type f \( -name '*.hpp' -o -name '*.cpp' \) -print0)
fi

if [ $bad -ne 0 ]; then
  echo "module order: FAILED (see lib/README.md)"
  exit 1
fi
echo "module order: $checked incise includes follow lib/README.md"
