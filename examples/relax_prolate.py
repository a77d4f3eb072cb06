"""Relax a prolate vesicle and plot its reduced energy e(t) and a slice of φ.

    python examples/relax_prolate.py                  # runs/prolate3d.json to stationarity
    python examples/relax_prolate.py --small          # a 32³ box, 30 steps (seconds)

Writes OUT/prolate.png (matplotlib, if installed: e against t, and the mid-plane slice
φ(x, y = centre, z), through the long axis) and OUT/phi.npy; prints the final state.
"""

import argparse
import pathlib

import vesicle

ROOT = pathlib.Path(__file__).resolve().parents[1]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--small", action="store_true", help="a small box and few steps")
    parser.add_argument("--out", default="out/examples/relax_prolate", help="output folder")
    args = parser.parse_args()
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    overrides = {}
    if args.small:
        overrides = {"n": [32, 32, 32], "initial.r0": 6.0, "max_steps": 30}
    scene = vesicle.Scene(ROOT / "runs" / "prolate3d.json", overrides=overrides)
    sim = vesicle.Simulation(scene)
    why = sim.run()
    print(
        f"{why}: step {sim.step_count}, t = {sim.t:.4g}, e = {sim.reduced_energy:.6f}, "
        f"v = {sim.reduced_volume:.4f}, residual = {sim.residual:.3e}"
    )
    phi = sim.phi
    sim.write_npy(out / "phi.npy")

    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib is not installed: no plot")
        return
    history = sim.history
    fig, (left, right) = plt.subplots(1, 2, figsize=(10, 4))
    left.plot(history["t"], history["reduced_energy"])
    left.set_xscale("symlog", linthresh=1.0)
    left.set_xlabel("t")
    left.set_ylabel("reduced energy e")
    mid = phi[:, phi.shape[1] // 2, :]
    image = right.imshow(mid.T, origin="lower", cmap="RdBu_r", vmin=-1, vmax=1)
    right.set_title("φ on the mid-plane y = centre")
    right.set_xlabel("x")
    right.set_ylabel("z")
    fig.colorbar(image, ax=right)
    fig.tight_layout()
    fig.savefig(out / "prolate.png", dpi=100)
    print(f"wrote {out / 'prolate.png'}")


if __name__ == "__main__":
    main()
