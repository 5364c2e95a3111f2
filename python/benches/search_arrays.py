"""`Tracer.search()` for 10^5 arrivals: a rectangular room to third order (with amplitudes),
one source, 4,000 listeners (25 arrivals each). Prints the medians over 7 runs of the search
with its result, and, where the package gives `Arrivals`, of `to_dicts()` and of iterating
(one dict at a time); a package whose `search()` gives a list times the list.

    python python/benches/search_arrays.py
"""

import time

import numpy as np

import eigenray

rng = np.random.default_rng(1)
receivers = np.column_stack([rng.uniform(0.2, 5.8, 4000), rng.uniform(0.2, 3.8, 4000)])
scene = eigenray.Scene({
    "media": {"air": {"speed": 343.0, "at": [3, 2]}},
    "interfaces": {
        "south": {"points": [[0, 0], [6, 0]]},
        "east": {"points": [[6, 0], [6, 4]]},
        "north": {"points": [[6, 4], [0, 4]]},
        "west": {"points": [[0, 4], [0, 0]]},
    },
    "sources": [[1.5, 1.2]],
    "receivers": receivers.tolist(),
    "search": {"max_steps": 3, "refract": False},
    "amplitudes": {"source": "point"},
})
tracer = eigenray.Tracer(scene)
arrays = hasattr(eigenray, "Arrivals")
rounds = []
for _ in range(7):
    t0 = time.perf_counter()
    arrivals = tracer.search()
    t1 = time.perf_counter()
    row = {"search()": t1 - t0}
    if arrays:
        arrivals.to_dicts()
        t2 = time.perf_counter()
        for _ in arrivals:
            pass
        row.update({"to_dicts()": t2 - t1, "iterating": time.perf_counter() - t2})
    rounds.append(row)
print(f"{len(arrivals)} arrivals, as {'Arrivals' if arrays else 'a list of dicts'}")
for key in rounds[0]:
    print(f"  {key}: median {1e3 * np.median([r[key] for r in rounds]):.1f} ms")
