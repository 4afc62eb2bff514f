#!/bin/sh
# Measure the seed cases with criterion and the element-cost study, and write both into
# BENCHMARKS.md between its markers. Run from the repository's root on an otherwise idle
# machine (about 6 minutes).
set -eu
cargo bench --bench increment -- --warm-up-time 1 --measurement-time 3 \
    '^(increment/[^/]*/(explicit|rapier_f64)$|floor/[^/]*/slices$)'
commit=$(git rev-parse --short HEAD)
date=$(date -u +%Y-%m-%d)
table=$(cargo run --release --quiet --example benchmark_table -- "$commit" "$date")
elements=$(cargo run --release --quiet -- scaling --study elements --out report/scaling --quiet |
    sed '/^written:/d')
splice() {
    # $1 marker name, $2 text: replace the lines between <!-- $1:begin --> and <!-- $1:end -->.
    awk -v name="$1" -v text="$2" '
        $0 == "<!-- " name ":begin -->" { print; print text; skip = 1; next }
        $0 == "<!-- " name ":end -->" { skip = 0 }
        !skip { print }
    ' BENCHMARKS.md > BENCHMARKS.md.new && mv BENCHMARKS.md.new BENCHMARKS.md
}
splice table "$table"
splice elements "$elements"
