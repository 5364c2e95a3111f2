"""A room's arrivals to order 3 as an echogram: every reflection path from the loudspeaker to
one listener, found by eigenray's search (no sequences written by hand).

    python echogram.py [echogram.png]
"""

import sys

import numpy as np

import eigenray

SPEED = 343.0
scene = eigenray.Scene({
    "media": {"air": {"speed": SPEED, "at": [3, 2]}},
    "interfaces": {
        "south": {"points": [[0, 0], [6, 0]]},
        "east": {"points": [[6, 0], [6, 4]]},
        "north": {"points": [[6, 4], [0, 4]]},
        "west": {"points": [[0, 4], [0, 0]]},
    },
    "sources": [[1.5, 1.2]],
    "receivers": [[4.4, 2.7]],
    "search": {"max_steps": 3, "refract": False},
})
arrivals = eigenray.Tracer(scene).search()  # numpy arrays, ordered by time

times = arrivals.time
orders = arrivals.order  # reflections of each arrival
# Level of each arrival relative to the direct sound: spherical spreading only (1/r).
level = 20 * np.log10(times[0] / times)
for order in range(4):
    print(f"order {order}: {np.sum(orders == order)} arrivals")
print(f"first {len(arrivals)} arrivals within {1e3 * times[-1]:.1f} ms")

if len(sys.argv) > 1:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (room, echo) = plt.subplots(1, 2, figsize=(11, 4), layout="constrained")
    eigenray.plot(scene, [a for a in arrivals if len(a["steps"]) <= 1], colour_by="path", ax=room)
    room.set_title("direct sound and first-order reflections")
    for order, colour in zip(range(4), ["black", "tab:blue", "tab:orange", "tab:green"]):
        chosen = orders == order
        echo.vlines(1e3 * times[chosen], -40, level[chosen], colors=colour, label=f"order {order}")
    echo.set_ylim(-20, 1)
    echo.set_xlabel("arrival time (ms)")
    echo.set_ylabel("level re direct sound (dB, 1/r spreading)")
    echo.legend()
    echo.set_title(f"echogram: {len(arrivals)} arrivals to order 3")
    fig.savefig(sys.argv[1], dpi=120)
    print(f"wrote {sys.argv[1]}")
