#!/usr/bin/env bash
# Re-create the committed charts and pictures of runs/results/ (every PNG, the SVG beside a chart,
# and the scenes' GIFs) by running the commands that produced them, then copy the figures of the
# manual (docs/src/figures/, copies of PNGs of runs/results/) again.
#
#   bash runs/regenerate_charts.sh            # the cheap groups (a few minutes in all)
#   bash runs/regenerate_charts.sh GROUP...   # those groups; `all` for every group
#   bash runs/regenerate_charts.sh --list     # the groups and what each costs
#
# Each command writes into $WORK/<group> (default out/regenerate, ignored by git); only the
# pictures are copied into runs/results/. The data files the commands write beside them (CSV,
# TXT) stay in $WORK: the committed ones are the record of the runs the manual quotes, and a
# rerun changes their wall times (and, where a chart plots wall time, the chart). Compare them
# with `diff -r` when a rerun should have changed the numbers. The binary is $VESICLE (default
# target/release/vesicle, built with `cargo build --release` when missing).
#
# Wall times on a busy 2-core machine (load average 6-8), measured on 2026-12-05 where marked,
# else estimated from the committed results' own record:
#   convergence      study convergence                                            74 s, measured
#   stability        study stability (the Δt × h map, α, the c0 axis)              22 s, measured
#   stability_ade    study ade (the ADE multiplier, implicit against lagged)       29 s, measured
#   pinning          study pinning (lattice pinning against h/ε)       ~17 min (1 007 s, loaded)
#   resolution       study resolution (error against wall time)         ~6 min (342 s, loaded)
#   precision        study precision (transient) + study stationary (Pareto)     104 s, measured
#   pear3d           run pear3d.json (40 000 steps), render --cut y --gif           11 s, measured
#   budding          study budding budding.json (41 relaxations, h = 2ε/3)   ~32 min (8.5 min CPU), measured
#   onset            study onset onset.json + onset_seeds.json (R0 20-28ε)   ~58 min (32 + 25.5, one thread), measured
#                    + onset_hessian{,_h1,_h05,_h05_r40}.json (seed-free, h/ε = 2/3, 1, 1/2)  ~45 min (21 + 3 + 5 + 10, one thread, loaded), measured
#                    + onset_bc{,_r32,_r40}.json (the bilayer couple's pear transition)  1 112 s + 1 721 s + 4 725 s (one thread each, beside other runs), measured 2026-12-07
#   heating          study heating heating.json (51 relaxations, 14 references)   220 s (one thread), measured
#   rates            study rates rates.json + rates3d.json + rates3d_box{,8,10}.json + rates3d_free{,_fine}.json + rates_free.json + rates_fine.json + rates_l6.json + rates3d_tension{,_fine}.json + rates3d_sigma10.json + rates3d_tension_l4.json + rates3d_sigma10_l5.json + rates{,3d}_inextensible.json + rates3d_mobility.json + rates3d_free_m016{,_r24}.json + rates3d_m016_r{24,28,28_s0,32}.json + rates3d_tension_l6{,_r72}.json + rates3d_tension_l2_m016{,_r48}.json + rates_mobility.json + rates3d_mobility_l3{,_fine}.json   747 s (two cores) + 2 519 s (recorded) + 1 848 s + 248 s + 428 s + 3 389 s + 6 681 s + 182 s + 2 935 s + 753 s + 2 300 s + 4 072 s + 2 114 s + 1 074 s + 1 265 s + 959 s + (see rates3d_inextensible's rates.txt) + 3 207 s + 4 042 s + 2 337 s + 1 458 s + 1 908 s + 5 083 s + 4 459 s + 1 663 s + 2 476 s + 2 422 s + 5 894 s + 553 s + 468 s + 958 s (one thread beside other runs, measured 2026-12-06 and -07)
#   shear            study shear shear.json + shear_box.json (2D)   3 036 s + 445 s on one thread beside other runs, measured 2026-12-06
#   shear3d          study shear shear3d.json + shear3d_box.json + shear3d_length.json (3D)   35 + 12 + 74 min on one thread beside two or three other runs, measured 2026-12-06
#   contrast         study rates rates_contrast.json + study shear shear_contrast.json (unequal viscosities)   2 123 s + 4 036 s on one thread (the second beside three other runs), measured 2026-12-06
#   axisym_c0        axisym --c0=-1,...,4 --nodes 481    1 667 s wall (720 s CPU, one thread, beside three other runs), measured 2026-12-06
#   axisym_bc        axisym --bc --da=0.70,...,1.40 --nodes 241        625 s (478 s CPU, one thread beside two or three other runs), measured
#   axisym_ade       axisym --ade 1.4 --da0=0.80,...,1.90 --nodes 241 680 s (530 s CPU, one thread beside two or three other runs), measured
#   diagram          diagram diagram.json, 84 cases, --jobs 2                     234 s, measured
#   diagram_fine     diagram diagram_fine.json, 81 cases           ~9-18 min (cases: 1 037 s)
#   diagram_c0       diagram diagram_c0.json, 165 cases           ~30-60 min (cases: 3 368 s)
#   diagram_c0_fine  diagram diagram_c0_fine.json, 165 cases      ~17-35 min (cases: 1 968 s)
#   diagram_ade      diagram diagram_ade.json, 60 cases (h = ε/2, R0 24-40ε)     13.5 min (cases: 1 594 s), measured
#   diagram_bc       diagram diagram_bc.json, 36 cases (h = ε/2, R0 24-40ε)  36.6 min at load 7-8 (cases: 4 032 s), measured; rerun 2026-12-06 on one thread beside two other runs: cases 3 323 s
#   diagram_bc_pear  diagram diagram_bc_pear.json, 9 cases (h = ε/2, R0 24-32ε)   55 min on one thread beside two other runs (cases: 3 237 s), measured 2026-12-06
#   budding3d        run budding3d.json (200 000 steps), measure, render    ~14 min (820 s recorded)
#   deflation3d      run deflation3d.json (215 000 steps), measure, render     280 s, measured
#   dumbbell3d       run dumbbell3d.json (150 000 steps), render  ~11 min (as budding3d, 3/4 the steps)
#   pearling3d       run pearling3d.json (200 000 steps), measure, render   ~62 min (recorded)
#   triaxial3d       run triaxial3d.json (L-BFGS, ~1 000 iterations), render        ~40 s, measured
#   starfish3d       run starfish3d.json (L-BFGS, ~2 000 iterations), render      141 s, measured
# The recorded scene times are of older builds (pear3d, recorded at 94 s, now takes 11 s). The
# default (cheap) groups are the first four.
set -euo pipefail
cd "$(dirname "$0")/.."

VESICLE=${VESICLE:-target/release/vesicle}
WORK=${WORK:-out/regenerate}
CHEAP=(convergence stability precision pear3d)
ALL=(convergence stability stability_ade pinning resolution precision pear3d budding onset heating rates shear shear3d contrast axisym_c0 axisym_bc
     axisym_ade diagram diagram_fine diagram_c0 diagram_c0_fine diagram_ade diagram_bc diagram_bc_pear budding3d deflation3d
     dumbbell3d pearling3d triaxial3d starfish3d)

# Run the program, echoing the command.
vesicle() {
    echo "+ vesicle $*" >&2
    "$VESICLE" "$@"
}

# keep FROM TO: copy one picture into runs/results/ (TO relative to it), and the SVG beside a
# chart when the committed one has an SVG.
keep() {
    cp "$1" "runs/results/$2"
    if [ -e "runs/results/${2%.png}.svg" ]; then
        cp "${1%.png}.svg" "runs/results/${2%.png}.svg"
    fi
}

# same_names FROM DIR: every committed picture under runs/results/DIR from the same path under
# FROM (a file the command no longer writes stops the script).
same_names() {
    local f
    git -C "runs/results/$2" ls-files -- '*.png' '*.svg' '*.gif' | while read -r f; do
        cp "$1/$f" "runs/results/$2/$f"
    done
}

# study KIND FILE: `vesicle study KIND runs/studies/FILE` into $WORK/<group>.
study() {
    vesicle study "$1" "runs/studies/$2" --out "$out" --force
}

# studies KIND NAME...: `study KIND` on each runs/studies/NAME.json into $WORK/NAME, its
# committed pictures (runs/results/NAME) replaced.
studies() {
    local kind=$1 name
    shift
    for name in "$@"; do
        out=$WORK/$name
        study "$kind" "$name.json"
        same_names "$out" "$name"
    done
}

# scene NAME: run runs/NAME.json into $WORK/NAME (the folder name is the frames' title).
scene() {
    vesicle run "runs/$1.json" --out "$out" --force --quiet
}

# frame STEP TO: the rendered frame of STEP of the scene in $out, kept as scenes/TO.
frame() {
    keep "$out/frames/frame_$(printf %08d "$1").png" "scenes/$2"
}

group_convergence() { studies convergence convergence; }
group_stability() { studies stability stability; }
group_stability_ade() { studies ade stability_ade; }
group_pinning() { studies pinning pinning; }
group_resolution() { studies resolution resolution; }
group_precision() {
    study precision precision.json
    keep "$out/precision_transient.png" precision/precision_transient.png
    out=$WORK/stationary
    study stationary stationary.json
    keep "$out/stationary_pareto.png" precision/precision_stationary.png
}
group_pear3d() {
    scene pear3d
    vesicle render "$out" --cut y --gif
    frame 2000 pear3d_02000.png
    frame 18000 pear3d_18000.png
    frame 40000 pear3d_40000.png
    cp "$out/movie.gif" runs/results/scenes/pear3d.gif
}
group_budding() {
    study budding budding.json
    for c in budding_neck_eps budding_neck_r0 budding_skewness; do keep "$out/$c.png" "budding/$c.png"; done
}
group_onset() {
    studies onset onset onset_seeds onset_hessian onset_hessian_h1 onset_hessian_h05 onset_hessian_h05_r40 onset_bc onset_bc_r32 onset_bc_r40
}
group_heating() { studies heating heating; }
group_rates() { studies rates rates rates3d rates3d_box rates3d_box8 rates3d_box10 rates3d_free rates3d_free_fine rates_free rates_fine rates_l6 rates3d_tension rates3d_tension_fine rates3d_tension_l4 rates3d_sigma10 rates3d_sigma10_l5 rates_inextensible rates3d_inextensible rates3d_mobility rates3d_free_m016 rates3d_free_m016_r24 rates3d_m016_r24 rates3d_m016_r28 rates3d_m016_r28_s0 rates3d_m016_r32 rates3d_tension_l6 rates3d_tension_l6_r72 rates3d_tension_l2_m016 rates3d_tension_l2_m016_r48 rates_mobility rates3d_mobility_l3 rates3d_mobility_l3_fine; }
group_shear() { studies shear shear shear_box; }
group_shear3d() { studies shear shear3d shear3d_box shear3d_length; }
group_contrast() {
    studies rates rates_contrast
    studies shear shear_contrast
}
# seq_list FROM STEP COUNT: the comma-separated list FROM, FROM + STEP, … (COUNT values).
seq_list() {
    awk -v a="$1" -v d="$2" -v n="$3" 'BEGIN { for (i = 0; i < n; i++) printf "%s%.2f", (i ? "," : ""), a + d * i }'
}
group_axisym_bc() {
    vesicle axisym --bc --da="$(seq_list 0.70 0.01 71)" --v-min 0.6 --v-max 0.98 --dv 0.02 \
        --nodes 241 --out "$out" --force
    same_names "$out" axisym_bc
}
group_axisym_ade() {
    vesicle axisym --ade 1.4 --da0="$(seq_list 0.80 0.02 56)" --v-min 0.6 --v-max 0.98 --dv 0.02 \
        --nodes 241 --out "$out" --force
    same_names "$out" axisym_ade
}
group_axisym_c0() {
    vesicle axisym --c0=-1,-0.5,0,0.5,1,1.5,2,2.5,3,3.5,4 --nodes 481 --out "$out" --force
    same_names "$out" axisym_c0
}
diagram() {
    vesicle diagram "runs/$1.json" --out "$out" --jobs 2 --force
    same_names "$out" "$1"
}
group_diagram() { diagram diagram; }
group_diagram_fine() { diagram diagram_fine; }
group_diagram_c0() { diagram diagram_c0; }
group_diagram_c0_fine() { diagram diagram_c0_fine; }
group_diagram_ade() { diagram diagram_ade; }
group_diagram_bc() { diagram diagram_bc; }
group_diagram_bc_pear() { diagram diagram_bc_pear; }
group_budding3d() {
    scene budding3d
    vesicle measure "$out" --force
    vesicle render "$out" --cut y
    keep "$out/neck.png" scenes/budding3d_neck.png
    frame 10000 budding3d_010000.png
    frame 110000 budding3d_110000.png
    frame 200000 budding3d_200000.png
}
group_deflation3d() {
    scene deflation3d
    vesicle measure "$out" --force
    vesicle render "$out" --cut y --gif
    keep "$out/neck.png" scenes/deflation3d_neck.png
    frame 140000 deflation3d_140000.png
    frame 180000 deflation3d_180000.png
    frame 215000 deflation3d_215000.png
    cp "$out/movie.gif" runs/results/scenes/deflation3d.gif
}
group_dumbbell3d() {
    scene dumbbell3d
    vesicle render "$out" --cut y
    frame 150000 dumbbell3d_150000.png
}
# last_frame TO: the rendered final state of the scene in $out (an L-BFGS run's last step is
# not fixed in advance), kept as scenes/TO.
last_frame() {
    local f
    f=$(ls "$out"/frames/frame_*.png | tail -n 1)
    keep "$f" "scenes/$1"
}
group_triaxial3d() {
    scene triaxial3d
    vesicle render "$out"
    frame 0 triaxial3d_seed.png
    last_frame triaxial3d_final.png
}
group_starfish3d() {
    scene starfish3d
    vesicle render "$out"
    frame 0 starfish3d_seed.png
    last_frame starfish3d_final.png
}
group_pearling3d() {
    scene pearling3d
    vesicle measure "$out" --force
    vesicle render "$out" --cut y
    keep "$out/neck.png" scenes/pearling3d_neck.png
    frame 60000 pearling3d_060000.png
    frame 110000 pearling3d_110000.png
    frame 200000 pearling3d_200000.png
}

# The manual's figures: docs/src/figures/NAME from runs/results/PATH.
FIGURES=(
    axisym_c0_phase.png=axisym_c0/phase.png
    rates_mobility.png=rates3d_mobility/rates.png
    axisym_bc_phase.png=axisym_bc/phase.png
    axisym_ade_phase.png=axisym_ade/phase.png
    budding_neck_r0.png=budding/budding_neck_r0.png
    budding_skewness.png=budding/budding_skewness.png
    onset_eps.png=onset/onset_eps.png
    onset_skewness.png=onset/onset_skewness.png
    onset_seeds_skewness.png=onset_seeds/onset_skewness.png
    onset_eigenvalue.png=onset_hessian/onset_eigenvalue.png
    onset_bc_eigenvalue.png=onset_bc/onset_eigenvalue.png
    heating_neck.png=heating/heating_neck.png
    shear_contrast.png=shear_contrast/inclination_contrast.png
    heating_w.png=heating/heating_w.png
    heating_w_error.png=heating/heating_w_error.png
    heating_departure.png=heating/heating_departure.png
    heating_shape_03.png=heating/shape_03_da0_1.550.png
    heating_shape_08.png=heating/shape_08_da0_1.640.png
    heating_shape_12.png=heating/shape_12_da0_1.550.png
    convergence_eps.png=convergence/convergence_eps.png
    convergence_space.png=convergence/convergence_space.png
    convergence_space_semilog.png=convergence/convergence_space_semilog.png
    convergence_sphere.png=convergence/convergence_sphere.png
    convergence_time.png=convergence/convergence_time.png
    diagram.png=diagram/diagram.png
    errors.png=diagram/errors.png
    thumbnails.png=diagram/thumbnails.png
    diagram_c0_errors.png=diagram_c0/errors.png
    diagram_c0_phase.png=diagram_c0/phase.png
    diagram_c0_fine_errors.png=diagram_c0_fine/errors.png
    diagram_c0_fine_phase.png=diagram_c0_fine/phase.png
    precision_stationary.png=precision/precision_stationary.png
    precision_transient.png=precision/precision_transient.png
    stability_alpha.png=stability/stability_alpha.png
    stability_c0.png=stability/stability_c0.png
    stability_map.png=stability/stability_map.png
    stability_ade.png=stability_ade/stability_ade.png
    pinning.png=pinning/pinning.png
    resolution.png=resolution/resolution.png
    diagram_ade_phase.png=diagram_ade/phase.png
    diagram_ade_errors.png=diagram_ade/errors.png
    diagram_bc_errors.png=diagram_bc/errors.png
    diagram_bc_pear_thumbnails.png=diagram_bc_pear/thumbnails.png
    budding3d_010000.png=scenes/budding3d_010000.png
    budding3d_110000.png=scenes/budding3d_110000.png
    budding3d_200000.png=scenes/budding3d_200000.png
    budding3d_neck.png=scenes/budding3d_neck.png
    deflation3d_140000.png=scenes/deflation3d_140000.png
    deflation3d_180000.png=scenes/deflation3d_180000.png
    deflation3d_215000.png=scenes/deflation3d_215000.png
    deflation3d_neck.png=scenes/deflation3d_neck.png
    dumbbell3d_150000.png=scenes/dumbbell3d_150000.png
    pear3d_02000.png=scenes/pear3d_02000.png
    pear3d_18000.png=scenes/pear3d_18000.png
    pear3d_40000.png=scenes/pear3d_40000.png
    pearling3d_060000.png=scenes/pearling3d_060000.png
    pearling3d_110000.png=scenes/pearling3d_110000.png
    pearling3d_200000.png=scenes/pearling3d_200000.png
    pearling3d_neck.png=scenes/pearling3d_neck.png
    triaxial3d_seed.png=scenes/triaxial3d_seed.png
    triaxial3d_final.png=scenes/triaxial3d_final.png
    starfish3d_seed.png=scenes/starfish3d_seed.png
    starfish3d_final.png=scenes/starfish3d_final.png
)

if [ "${1:-}" = "--list" ]; then
    sed -n '/^# Wall times/,/^# default (cheap)/p' "$0"
    exit 0
fi
groups=("$@")
[ ${#groups[@]} -eq 0 ] && groups=("${CHEAP[@]}")
[ "${groups[*]}" = "all" ] && groups=("${ALL[@]}")
for g in "${groups[@]}"; do
    declare -F "group_$g" >/dev/null || { echo "unknown group $g (see --list)" >&2; exit 2; }
done
[ -x "$VESICLE" ] || cargo build --release
for g in "${groups[@]}"; do
    out=$WORK/$g
    mkdir -p "$WORK"
    start=$SECONDS
    "group_$g"
    echo "== $g: $((SECONDS - start)) s" >&2
done
for f in "${FIGURES[@]}"; do
    cp "runs/results/${f#*=}" "docs/src/figures/${f%%=*}"
done
