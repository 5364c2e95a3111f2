"""A room's echogram to 30 orders: every reflection path up to 30 walls from a loudspeaker to
a listener in a 6 m × 4 m room whose walls absorb 10 % of the energy
(`examples/scenes/room_orders.json`), drawn with `eigenray.plotting.echogram`. Past 10 orders
the orders are keyed by a colour bar, one colour each, and the time axis starts just before the
direct sound.

    python room_echogram.py [room_echogram.png]
"""

import pathlib
import sys

import numpy as np

import eigenray

SCENE = pathlib.Path(__file__).resolve().parents[2] / "examples" / "scenes" / "room_orders.json"

scene = eigenray.Scene(SCENE)
echoes = eigenray.Tracer(scene).echoes()
orders = np.asarray(echoes["order"])
print(f"{len(orders)} arrivals of orders 0 to {orders.max()}; "
      f"{np.sum(orders == 30)} of them reflect 30 times")

if len(sys.argv) > 1:
    import matplotlib

    matplotlib.use("Agg")
    from eigenray.plotting import echogram

    ax = echogram(echoes)
    ax.set_title(f"A 6 m × 4 m room, walls absorbing 10 %: {len(orders)} arrivals to order 30",
                 fontsize=10)
    ax.figure.savefig(sys.argv[1], dpi=110)
    print(f"wrote {sys.argv[1]}")
