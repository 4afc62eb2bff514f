#!/bin/sh
# Measure the seed cases with criterion, count their instructions per increment with valgrind,
# run the chain study and the element-cost study, and write them into BENCHMARKS.md between
# its markers and into report/scaling/. Run from the repository's root on an otherwise idle
# machine (about 30 minutes), at a commit: every figure records the commit it measured, and
# tests/figures_current.rs fails once the engines' sources differ from it.
set -eu
if ! git diff --quiet HEAD -- src Cargo.toml Cargo.lock; then
    echo "error: uncommitted changes under src/ or in Cargo.toml/Cargo.lock; commit them first," >&2
    echo "so that the figures name the commit they measured" >&2
    exit 2
fi
if ! command -v valgrind > /dev/null; then
    echo "error: valgrind not found; it counts the instructions per increment (Debian: apt install valgrind)" >&2
    exit 2
fi
cargo bench --bench increment -- --warm-up-time 1 --measurement-time 3 \
    '^(increment/[^/]*/(explicit|rapier_f64)$|floor/[^/]*/slices$)'
commit=$(git rev-parse --short HEAD)
date=$(date -u +%Y-%m-%d)
table=$(cargo run --release --quiet --example benchmark_table -- "$commit" "$date")
instructions=$(cargo run --release --quiet --example increment_instructions -- "$commit" "$date")
chain=$(cargo run --release --quiet -- scaling --study chain --out report/scaling --quiet |
    sed '/^written:/d')
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
splice instructions "$instructions"
splice chain "$(printf 'Measured at commit %s, %s, by `scripts/benchmarks.sh`.\n\n```text\n%s\n```' "$commit" "$date" "$chain")"
splice elements "$elements"
