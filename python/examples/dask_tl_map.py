"""A transmission-loss map on a Dask cluster, in receiver blocks: Lloyd's mirror (a 150 Hz
point source 25 m under a pressure-release sea surface) over 2 km of range and 100 m of
depth, 200,000 receivers cut into blocks of 10,000. Each task gets the pickled `Tracer` (its
scene's JSON, a block's worth of receivers) and a block, moves the tracer's receivers there
and computes the block's transmission loss; the blocks put together equal the map computed
in one process, bit for bit. Needs `dask[distributed]`; on a real cluster, give `Client` the
scheduler's address instead of a `LocalCluster`.

    python dask_tl_map.py [dask_tl_map.png]
"""

import sys
import time

import numpy as np
from dask.distributed import Client, LocalCluster

import eigenray

FREQUENCY, SPEED, DEPTH = 150.0, 1500.0, 25.0
BLOCK = 10000


def lloyd(receivers):
    """The scene, with these receivers."""
    return eigenray.Scene({
        "media": {"water": {"speed": SPEED}},
        "background": "water",
        "interfaces": {
            "surface": {"points": [[-10, 0], [2100, 0]], "reflection": "pressure-release"},
        },
        "sources": [[0.0, -DEPTH]],
        "receivers": np.asarray(receivers).tolist(),
        "search": {"max_steps": 1, "refract": False},
        "amplitudes": {"source": "point", "frequency": FREQUENCY},
    })


def block_tl(tracer, block):
    """One task: the tracer (unpickled for this task alone, so that moving its receivers
    touches no other task's) moved to `block` (BLOCK receivers, the scene's count)."""
    tracer.set_receivers(block)
    return tracer.transmission_loss()[0]


def main():
    x, y = np.meshgrid(np.arange(2.5, 2000.1, 2.5), -np.arange(0.4, 100.1, 0.4))
    receivers = np.column_stack([x.ravel(), y.ravel()])
    n = len(receivers)

    start = time.perf_counter()
    whole = eigenray.Tracer(lloyd(receivers)).transmission_loss()[0]
    one = time.perf_counter() - start

    # Every block has the scene's BLOCK receivers: the last one is padded with copies of
    # its last receiver, whose results are dropped.
    padded = np.concatenate([receivers, np.repeat(receivers[-1:], -n % BLOCK, axis=0)])
    blocks = np.split(padded, len(padded) // BLOCK)
    tracer = eigenray.Tracer(lloyd(blocks[0]))
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster, Client(cluster) as client:
        client.submit(np.zeros, 1).result()  # the workers are up
        start = time.perf_counter()
        futures = [client.submit(block_tl, tracer, block, pure=False) for block in blocks]
        tl = np.concatenate(client.gather(futures))[:n]
        cluster_time = time.perf_counter() - start

    assert np.array_equal(tl, whole), "the cluster's map differs from the one-process map"
    print(f"{n} receivers: one process {one:.2f} s, Dask LocalCluster (2 worker processes, "
          f"{len(blocks)} blocks of {BLOCK}) {cluster_time:.2f} s; the maps are equal bit for bit")

    picture = sys.argv[1] if len(sys.argv) > 1 else "dask_tl_map.png"
    from eigenray.plotting import tl_map

    ax = tl_map(receivers, tl, title=f"Lloyd's mirror at {FREQUENCY:.0f} Hz on a Dask cluster "
                f"({len(blocks)} blocks of {BLOCK} receivers)")
    ax.figure.savefig(picture, dpi=120)
    print(f"wrote {picture}")


if __name__ == "__main__":
    main()
