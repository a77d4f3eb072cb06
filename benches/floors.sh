#!/usr/bin/env bash
# The step benches against the C floors of ../shared/bench, interleaved: for every configuration,
# ROUNDS times in turn, the C program, our criterion bench (filtered to that one bench), the C
# program again. `spectral_unconstrained` is our spectral step as fft_limit times its own: the
# area not held (σ = 0), so without the projection's sweep. Prints our median, the two C
# medians around it and their ratio; then per configuration the median ratio and its range. On a
# shared machine a C median can move by half between two runs a minute apart, so a ratio is only
# worth the C runs taken beside it.
#
# Then, in the same session, the two ratios of the route to stationary shapes (docs/src/performance.md):
# one L-BFGS iteration over one conserved SBDF1 step on the 48³ prolate (criterion `relax/`, 1
# and 2 threads), and the wall time of adaptive SBDF1 over L-BFGS to the energy 1e-6 above F*
# (`vesicle study stationary runs/prolate3d_full.json`, 1 thread), ROUNDS times each.
#
# Needs the C programs built first (README, "Performance"):
#   make -C ../shared/bench O="$PWD/target/cbench"
# Usage, from the project root: bash benches/floors.sh [ROUNDS]   (default 3; about 4 min a round)
set -euo pipefail
rounds=${1:-3}
cbench=target/cbench
[[ -x $cbench/fft_limit && -x $cbench/fd_limit ]] || {
    echo "build the C floors first: make -C ../shared/bench O=\"\$PWD/$cbench\"" >&2
    exit 2
}

# The C median (ms) of one configuration: METHOD N THREADS.
c_median() {
    local line
    if [[ $1 == fd ]]; then
        line=$($cbench/fd_limit -t "$3" -n "$2" -v fused -s 1 | head -1)
        sed -E 's/.*"ms_median": ([0-9.e+-]+).*/\1/' <<<"$line"
    else
        line=$($cbench/fft_limit -t "$3" -n "$2" -s 1 | head -1)
        sed -E 's/.*"step_ms_median": ([0-9.e+-]+).*/\1/' <<<"$line"
    fi
}

# The median (ms) of criterion's first `time: [low median high]` line on stdin.
median_ms() {
    grep -m1 -o 'time: *\[[^]]*\]' |
        awk '{ v = $4; if ($5 == "µs") v /= 1000; if ($5 == "s") v *= 1000; print v }'
}

# Our criterion median (ms) of one configuration. The bench's output is captured whole first:
# piped straight into `grep -m1`, cargo could be stopped by SIGPIPE, which `pipefail` reports.
our_median() {
    local out
    out=$(cargo bench -q --bench step -- --warm-up-time 1 --measurement-time 3 \
        "step/$1/full/$2\\^3/t$3\$" 2>/dev/null)
    grep -m1 -A1 "^step/" <<<"$out" | median_ms
}

# Criterion's median (ms) of the bench named `relax/$1` in the output $2.
relax_median() {
    grep -A1 "^relax/$1\$" <<<"$2" | median_ms
}

configs=("spectral 64 1" "spectral 64 2" "spectral 128 1" "spectral 128 2"
    "spectral_unconstrained 64 1" "spectral_unconstrained 64 2"
    "spectral_unconstrained 128 1" "spectral_unconstrained 128 2"
    "fd 64 1" "fd 64 2" "fd 128 1" "fd 128 2")
cargo bench --bench step --no-run -q
results=$(mktemp)
trap 'rm -f "$results"' EXIT
for ((r = 1; r <= rounds; r++)); do
    for c in "${configs[@]}"; do
        read -r method n threads <<<"$c"
        before=$(c_median "$method" "$n" "$threads")
        ours=$(our_median "$method" "$n" "$threads")
        after=$(c_median "$method" "$n" "$threads")
        ratio=$(awk -v o="$ours" -v a="$before" -v b="$after" 'BEGIN { printf "%.2f", 2 * o / (a + b) }')
        printf '%-22s %4s³ t%s  ours %8.3f ms  C %8.3f %8.3f ms  ratio %s\n' \
            "$method" "$n" "$threads" "$ours" "$before" "$after" "$ratio" | tee -a "$results"
    done
done
echo
echo "median ratio (range) over $rounds rounds"
for c in "${configs[@]}"; do
    read -r method n threads <<<"$c"
    grep -E "^$method +$n³ t$threads " "$results" | awk '{ print $NF }' | sort -n |
        awk -v c="$method $n³ t$threads" '{ v[NR] = $1 }
            END { m = (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2
                  printf "%-32s %.2f× (%.2f–%.2f)\n", c, m, v[1], v[NR] }'
done

echo
echo "the route to the 48³ prolate, $rounds rounds"
cargo build --release -q
route_dir=$(mktemp -d)
trap 'rm -f "$results"; rm -rf "$route_dir"' EXIT
for ((r = 1; r <= rounds; r++)); do
    out=$(cargo bench -q --bench step -- --warm-up-time 1 --measurement-time 3 'relax/' 2>/dev/null)
    for t in 1 2; do
        it=$(relax_median "lbfgs_iteration/48^3/t$t" "$out")
        st=$(relax_median "conserved_step/48^3/t$t" "$out")
        awk -v i="$it" -v s="$st" -v t="$t" \
            'BEGIN { printf "L-BFGS iteration / SBDF1 step, t%s   %.3f / %.3f ms = %.2f\n", t, i, s, i / s }'
    done
    target/release/vesicle study stationary runs/prolate3d_full.json --out "$route_dir/r$r" --force |
        grep -o 'L-BFGS [0-9.]*x less wall time than SBDF1' |
        sed 's/$/ to the energy 1e-6 above F*, t1/'
done
