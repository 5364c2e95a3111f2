"""A room's impulse response and echogram: an L-shaped room whose walls absorb 10 % of the
energy, every reflection path up to 8 walls found by eigenray's search, each arrival's
amplitude (spreading and wall coefficients), the response at 16 kHz written as a WAV file
and drawn above its echogram.

    python room_response.py [room_response.png] [room_response.wav]
"""

import sys

import matplotlib.pyplot as plt
import numpy as np
from scipy.io import wavfile

import eigenray
from eigenray.plotting import echogram

RATE = 16000
corners = [[0, 0], [6, 0], [6, 3], [3.5, 3], [3.5, 5], [0, 5]]
walls = {
    f"wall {i}": {
        "points": [corners[i], corners[(i + 1) % len(corners)]],
        "reflection": {"absorption": 0.1},
    }
    for i in range(len(corners))
}
scene = eigenray.Scene({
    "media": {"air": {"speed": 343.0}},
    "background": "air",
    "interfaces": walls,
    "sources": [[1.2, 1.0]],
    "receivers": [[5.1, 2.2]],
    "search": {"max_steps": 8, "refract": False},
    "amplitudes": {"source": "point"},
    "impulse_response": {"rate": RATE, "duration": 0.16},
})
tracer = eigenray.Tracer(scene)
h = tracer.impulse_response()[0, 0]  # sample n at time n / RATE
echoes = tracer.echoes()

picture = sys.argv[1] if len(sys.argv) > 1 else "room_response.png"
sound = sys.argv[2] if len(sys.argv) > 2 else picture.rsplit(".", 1)[0] + ".wav"
wavfile.write(sound, RATE, (h / np.abs(h).max()).astype(np.float32))

fig, (top, bottom) = plt.subplots(2, 1, figsize=(8, 7), layout="constrained", sharex=True)
top.plot(np.arange(len(h)) / RATE, h, color="0.2", linewidth=0.8)
top.set_ylabel("pressure (unit source)")
top.set_title(f"Impulse response at {RATE} Hz: {len(echoes['time'])} arrivals up to 8 walls",
              fontsize=10)
top.grid(alpha=0.3)
echogram(echoes, ax=bottom)
fig.savefig(picture, dpi=120)
print(f"wrote {picture} and {sound}: {len(echoes['time'])} arrivals, "
      f"peak {np.abs(h).max():.4f} at {np.argmax(np.abs(h)) / RATE * 1000:.2f} ms")
