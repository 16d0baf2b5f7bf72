#!/usr/bin/env bash
# Interleaved A/B of two lenspath binaries (say, before and after a refactor),
# one thread, five rounds: a render of the default scene, the README's
# autofocus, and the dragon in the CS184 box (needs ../shared). Prints the
# seconds of each command per binary and round; compare best and median.
set -euo pipefail
cd "$(dirname "$0")/.."
old=${1:?usage: bench/ab_refactor.sh OLD_BINARY NEW_BINARY}
new=${2:?usage: bench/ab_refactor.sh OLD_BINARY NEW_BINARY}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
seconds() {
    local t0 t1
    t0=$(date +%s.%N)
    "$@" >/dev/null 2>&1
    t1=$(date +%s.%N)
    python3 -c "print(f'{$t1 - $t0:.3f}')"
}
for round in 1 2 3 4 5; do
    for tag in old new; do
        bin=$old
        [ "$tag" = new ] && bin=$new
        render=$(seconds "$bin" render --threads 1 --spp 16 --out "$out/$tag.png")
        focus=$(seconds "$bin" autofocus --patch 0.52,0.70,0.10,0.12 --strategy fast --threads 1)
        dragon=$(seconds "$bin" render scenes/cbdragon.toml --allow-read ../shared --threads 1 --spp 8 --out "$out/$tag-dragon.png")
        echo "round $round $tag: render $render autofocus $focus dragon $dragon"
    done
done
