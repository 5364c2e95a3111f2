"""Writes a scene of N receivers over a floor with one vertex (a kink of 1 mm at x = 0):
`specular` asks for its reflection, `diffract` for the diffraction at its vertex, both with
point-source amplitudes at 500 Hz. `python benches/diffraction_cost.py KIND N > scene.json`,
then time `eigenray solve scene.json --format npy --rays out.npy` (docs/method.md)."""
import json, sys
n = int(sys.argv[2])
kind = sys.argv[1]
recv = [[-50 + 100 * i / (n - 1), 5.0 + (i % 7) * 0.5] for i in range(n)]
step = {"reflect": "floor"} if kind == "specular" else {"diffract": "floor", "vertex": 1}
scene = {
    "media": {"air": {"speed": 343}},
    "interfaces": {"floor": {"points": [[-100, 0], [0, 0.001], [100, 0]], "reflection": "rigid"}},
    "sources": [[-20, 3]], "receivers": recv,
    "paths": [{"steps": [step], "media": ["air", "air"]}],
    "amplitudes": {"source": "point", "frequency": 500},
}
print(json.dumps(scene))
