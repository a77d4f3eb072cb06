#!/usr/bin/env bash
# The checks and timings of issue 45 in one run, on a machine with an NVIDIA GPU and many cores:
#
#   bash benches/device_check.sh [BIN] [OUT]
#
# BIN is a release binary built with `cargo build --release --features gpu` (default
# target/release/vesicle; it can be built elsewhere: the CUDA libraries are loaded at run time).
# Writes OUT/device_check.json (default out/device_check) and prints it. What it measures:
#
# 1. Agreement: runs/prolate3d_full.json (48³ full box) on the CPU (1 thread) and the GPU, the
#    same scene: max|Δφ| after 100 fixed SBDF1 steps and after 100 adaptive SBDF2 steps (target
#    1e-10), and the stationary energy of the prolate (adaptive SBDF2 to residual 1e-8, the CPU
#    on every core; target 1e-9 relative).
# 2. Step time: the spectral SBDF1 step with no area constraint (the floor's step) and with the
#    exact projection, at 128³, 256³ and 512³, from the run's own wall clock between two records
#    (set-up left out); the CPU step at 256³ on every core for the GPU/CPU ratio.
# 0. Conformance: each GPU pass against its CPU pass on random fields, and whole runs
#    (`cargo test --release --features gpu --lib gpu -- --ignored`, the tests of
#    src/engines/gpu/conformance.rs; needs cargo on the machine, else skipped and said so).
# 3. The floors, in the same run: FLOORS/gpu_step.py (CuPy and cuFFT) when CuPy imports, and
#    FLOORS/fft_limit (FFTW, built here with `make` when FFTW's headers are present) at 128³ and
#    256³ on 1, 4, 8 and 16 threads beside our CPU step on as many (no area constraint, the
#    floor's step). FLOORS defaults to ../shared/bench.
set -euo pipefail
bin=${1:-target/release/vesicle}
out=${2:-out/device_check}
floors=${FLOORS:-../shared/bench}
cores=$(nproc)
mkdir -p "$out"
scene=runs/prolate3d_full.json

run() { # NAME then --set overrides: one quiet run into $out/NAME (replaced)
    local name=$1
    shift
    "$bin" run "$scene" --out "$out/$name" --force --quiet "$@" >"$out/$name.log" 2>&1 || {
        echo "run $name failed:" >&2
        cat "$out/$name.log" >&2
        return 1
    }
}

conformance="skipped: no cargo"
if command -v cargo >/dev/null; then
    if cargo test --release --features gpu --lib gpu -- --ignored >"$out/conformance.log" 2>&1; then
        conformance="passed"
    else
        conformance="FAILED (see conformance.log)"
    fi
    tail -5 "$out/conformance.log"
fi

fixed=(--set max_steps=100 --set stop_residual=null --set adaptive=false)
for device in cpu gpu; do
    run "sbdf1_$device" --set device=$device --set threads=1 "${fixed[@]}" --set dt=0.05
    run "sbdf2_$device" --set device=$device --set threads=1 --set scheme=sbdf2 \
        --set max_steps=100 --set stop_residual=null
    threads=1
    [[ $device == cpu ]] && threads=$cores
    run "stationary_$device" --set device=$device --set threads=$threads --set scheme=sbdf2 \
        --set stop_residual=1e-8
done

steps() { # N STEPS AREA DEVICE THREADS
    run "step_$1_$3_$4_$5" --set "n=[$1,$1,$1]" --set device=$4 --set threads=$5 \
        --set "area.method=$3" "${fixed[@]}" --set dt=0.05 --set max_steps=$2 \
        --set output.record_every=10 --set output.png=false --set output.vti=false
}
for n in 128 256 512; do
    s=200
    [[ $n == 512 ]] && s=60
    steps $n $s none gpu 1
    steps $n $s projection gpu 1
done
for t in 1 4 8 16; do
    steps 128 40 none cpu $t
    steps 256 25 none cpu $t
done

fftw="null"
if [[ -f $floors/fft_limit.c ]] && make -C "$floors" O="$PWD/$out/cbench" >"$out/make.log" 2>&1; then
    fftw=$("$out/cbench/fft_limit" -t 1,4,8,16 -n 128,256 -s 2 | python3 -c '
import json, sys
print(json.dumps([json.loads(l) for l in sys.stdin if l.strip()]))')
fi

floor="null"
if python3 -c "import cupy" 2>/dev/null && [[ -f $floors/gpu_step.py ]]; then
    floor=$(python3 "$floors/gpu_step.py" 128 256 512 | python3 -c '
import json, sys
rows = [json.loads(l) for l in sys.stdin if l.strip()]
print(json.dumps(rows))')
fi

python3 - "$out" "$cores" "$floor" "$fftw" "$conformance" <<'PY'
import csv, json, sys
import numpy as np
out, cores, floor, fftw = sys.argv[1], int(sys.argv[2]), json.loads(sys.argv[3]), json.loads(sys.argv[4])
conformance = sys.argv[5]

def phi(name):
    return np.load(f"{out}/{name}/phi_final.npy")

def final(name):
    return json.load(open(f"{out}/{name}/summary.json"))["final"]

def step_ms(name):
    rows = list(csv.DictReader(open(f"{out}/{name}/timeseries.csv")))
    a, b = rows[1], rows[-1]  # from the first record after step 0: set-up left out
    return 1e3 * (float(b["wall_seconds"]) - float(a["wall_seconds"])) / (int(b["step"]) - int(a["step"]))

report = {"conformance": conformance, "agreement": {}, "step_ms": {}, "cpu_cores": cores, "floor": floor, "fftw": fftw}
for s in ["sbdf1", "sbdf2"]:
    report["agreement"][f"{s}_100_steps_max_abs_dphi"] = float(np.abs(phi(f"{s}_gpu") - phi(f"{s}_cpu")).max())
e_cpu, e_gpu = final("stationary_cpu")["energy"], final("stationary_gpu")["energy"]
report["agreement"]["stationary_energy"] = {"cpu": e_cpu, "gpu": e_gpu, "relative": abs(e_gpu - e_cpu) / abs(e_cpu)}
for n in [128, 256, 512]:
    for area in ["none", "projection"]:
        report["step_ms"][f"gpu_{n}_{area}"] = step_ms(f"step_{n}_{area}_gpu_1")
report["step_ms"]["cpu_256_none_16_threads"] = step_ms("step_256_none_cpu_16")
report["cpu_256_over_gpu_256"] = report["step_ms"]["cpu_256_none_16_threads"] / report["step_ms"]["gpu_256_none"]
if floor:
    for row in floor:
        if "n" in row:
            report["step_ms"][f"floor_{row['n']}"] = row["floor_ms"]
            report["step_ms"][f"gpu_over_floor_{row['n']}"] = report["step_ms"][f"gpu_{row['n']}_none"] / row["floor_ms"]
scaling = {}
for n in [128, 256]:
    for t in [1, 4, 8, 16]:
        ours = step_ms(f"step_{n}_none_cpu_{t}")
        row = {"vesicle_ms": ours}
        for c in fftw or []:
            if c.get("n") == n and c.get("threads") == t:
                row["fftw_ms"] = c["step_ms_median"]
                row["ratio"] = ours / c["step_ms_median"]
        scaling[f"{n}_t{t}"] = row
report["cpu_scaling"] = scaling
json.dump(report, open(f"{out}/device_check.json", "w"), indent=1)
print(json.dumps(report, indent=1))
PY
