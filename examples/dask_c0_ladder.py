"""A ladder in spontaneous curvature c0 spread over a Dask cluster (dask.distributed; here a
LocalCluster on this machine, the same code with a cluster's address elsewhere).

    pip install "dask[distributed]"
    python examples/dask_c0_ladder.py                  # c0 = 0 … 0.3, 2D ellipse, 96² box
    python examples/dask_c0_ladder.py --small          # 4 values on a 48² box
    python examples/dask_c0_ladder.py --scheduler tcp://host:8786

Each task relaxes one scene to stationarity and returns its final record (plain floats, so
nothing large crosses the network). Workers are separate *spawned* processes with one thread
each: the engine's thread pool (rayon) does not survive fork() — a forked child of a process
whose pool has started inherits a pool whose threads do not exist, and hangs at its first
parallel step — and one thread a worker keeps the cores from being oversubscribed. Running one
case at a time on one thread gives the same bits in the worker as in this process.
"""

import argparse

import dask
import vesicle
from dask.distributed import Client, LocalCluster


def scene(c0, n):
    """A 2D ellipse of reduced area 0.8 (R0 = n/6) at spontaneous curvature `c0`, relaxed with
    adaptive steps on the quarter box until RMS(μ − mean μ) < 1e-6."""
    return {
        "dim": 2,
        "n": [n, n],
        "h": 1.0,
        "eps": 1.0,
        "method": "spectral",
        "scheme": "sbdf1",
        "dt": 0.01,
        "adaptive": {"dt_max": 50.0},
        "max_steps": 3000,
        "stop_residual": 1e-6,
        "c0": c0,
        "initial": {"shape": "spheroid", "reduced_volume": 0.8, "r0": n / 6, "kind": "prolate"},
        "prepare_steps": 20,
        "symmetry": ["x", "y"],
    }


def relax(c0, n):
    """One rung: relax the scene of `c0` on one thread; its stop reason and final record."""
    sim = vesicle.Simulation(scene(c0, n), threads=1)
    why = sim.run()
    return {"c0": c0, "stopped": why, **sim.record}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--small", action="store_true", help="4 values on a 48² box")
    parser.add_argument("--workers", type=int, default=2, help="LocalCluster worker processes")
    parser.add_argument("--scheduler", help="address of a running scheduler (default: a LocalCluster)")
    args = parser.parse_args()
    n, c0s = (48, [0.0, 0.1, 0.2, 0.3]) if args.small else (96, [0.05 * k for k in range(7)])

    # Spawned, not forked, worker processes (see the module notes).
    dask.config.set({"distributed.worker.multiprocessing-method": "spawn"})
    if args.scheduler:
        client = Client(args.scheduler)
    else:
        cluster = LocalCluster(
            n_workers=args.workers, threads_per_worker=1, processes=True, dashboard_address=None
        )
        client = Client(cluster)
    with client:
        futures = client.map(relax, c0s, n=n)
        rows = client.gather(futures)
    print(f"{'c0':>6} {'stopped':>11} {'steps':>6} {'e':>10} {'v':>8} {'sigma':>11}")
    for r in rows:
        print(
            f"{r['c0']:6.3f} {r['stopped']:>11} {r['step']:6d} {r['reduced_energy']:10.6f} "
            f"{r['reduced_volume']:8.5f} {r['sigma']:11.4e}"
        )


if __name__ == "__main__":
    main()
