"""Bounded, interruptible calls (issue 29): Ctrl-C raises KeyboardInterrupt in a call that
would otherwise run on for long (a generous deadline only keeps a broken stop from hanging the
test run; no answer here depends on a clock), calls from several threads at once all succeed, complex numbers and a bad `progress` are a
TypeError, and inputs too large for the memory raise MemoryError (or a clear EigenrayError)
instead of aborting the interpreter. The long and the large calls run in subprocesses, so
that an abort or a hang cannot take the test runner with it."""

import math
import os
import signal
import subprocess
import sys
import textwrap
import threading
import time

import numpy as np
import pytest

import eigenray


def walls(k, sources, receivers, **extra):
    """Two wavy walls of 50 segments and a path of `k` reflections between them (the
    adversarial scenes of benches/adversarial_scenes.py)."""

    def wall(y0, phase):
        xs = [10.0 * i / 50 for i in range(51)]
        return [[x, y0 + 0.15 * math.sin(3.1 * x + phase) + 0.05 * math.sin(7.3 * x)] for x in xs]

    steps = [{"reflect": "floor" if i % 2 == 0 else "roof"} for i in range(k)]
    scene = {
        "media": {"air": {"speed": 1.0}},
        "interfaces": {"floor": {"points": wall(0.0, 0.0)}, "roof": {"points": wall(2.0, 1.3)}},
        "sources": sources,
        "receivers": receivers,
        "paths": [{"steps": steps, "media": ["air"] * (k + 1)}],
    }
    scene.update(extra)
    return scene


# A child process: builds `SETUP`, says READY, runs `CALL`; prints when KeyboardInterrupt came.
CHILD = """
import json, math, sys, time
import numpy as np
import eigenray
{walls}
{setup}
print("READY", flush=True)
try:
    {call}
    print("FINISHED", flush=True)
except KeyboardInterrupt:
    print("INTERRUPTED", flush=True)
"""

FALLBACK_GRID = """
n = 60
sources = [[1.0 + 4.0 * i / n, -1.0] for i in range(n)]
receivers = [[9.0 - 4.0 * i / n, 1.1] for i in range(n)]
tracer = eigenray.Tracer(eigenray.Scene(walls(12, sources, receivers)))
"""

EVERY_PATH = """
scene = walls(10, [[1.0, 1.0], [1.2, 1.0]], [[9.0, 1.1], [8.8, 1.1]],
              solver={"stationary": "all", "max_work": 2 ** 32})
tracer = eigenray.Tracer(eigenray.Scene(scene))
"""

SEARCH = """
scene = walls(0, [[1.0, 1.0]], [[9.0, 1.1]], solver={"max_work": 2 ** 32},
              search={"max_steps": 6, "refract": False, "vertex": True})
scene["media"]["air"]["at"] = [5.0, 1.0]
scene["paths"] = []
tracer = eigenray.Tracer(eigenray.Scene(scene))
"""

PAIRS = """
n = 3000
tracer = eigenray.Tracer(eigenray.Scene(walls(12, [[1.0, -1.0]], [[9.0, 1.1]])))
sources = np.column_stack([np.linspace(1, 5, n), np.full(n, -1.0)])
receivers = np.column_stack([np.linspace(9, 5, n), np.full(n, 1.1)])
"""

# An E-shaped room's every arrival to 0.6 s at eight listeners: millions of beams, seconds.
LATE_ROOM = """
corners = [[0, 0], [0, 5], [1, 5], [1, 2], [2, 2], [2, 5], [3, 5], [3, 0], [2, 0], [2, 1],
           [1, 1], [1, 0]]
tracer = eigenray.Tracer(eigenray.Scene({
    "media": {"air": {"speed": 343.0, "at": [0.5, 0.5]}},
    "interfaces": {"room": {"points": corners, "closed": True}},
    "sources": [[0.5, 0.5]],
    "receivers": [[2.5, 4.5], [1.5, 1.5], [0.5, 4.5], [2.5, 0.5], [0.5, 2.5], [2.5, 2.5],
                  [0.6, 1.5], [0.4, 3.5]],
    "search": {"max_time": 0.6}, "amplitudes": {"source": "point"},
}))
"""

# A rectangular room's 2 × 10^5 echoes (1,000 listeners, found in a fraction of a second),
# each a pulse of 10,001 taps: the rendering alone takes seconds.
LONG_RENDER = """
tracer = eigenray.Tracer(eigenray.Scene({
    "media": {"air": {"speed": 343.0, "at": [1.0, 1.0]}},
    "interfaces": {"room": {"points": [[0, 0], [6, 0], [6, 4], [0, 4]], "closed": True}},
    "sources": [[1.0, 1.0]], "receivers": [[0.5 + 0.005 * i, 2.5] for i in range(1000)],
    "search": {"max_time": 0.12}, "amplitudes": {"source": "point"},
}))
"""


# How long the interrupted child may take to end: a net for a stop that does not work (one
# that works ends the child within a fraction of a second), never a check of speed.
INTERRUPT_DEADLINE = 120


def interrupt(setup, call):
    """Runs `call` after `setup` in a child; sends SIGINT once it has run 0.5 s. Returns what
    the child printed after READY: `INTERRUPTED` when KeyboardInterrupt was raised."""
    source = CHILD.format(
        walls=textwrap.dedent(
            __import__("inspect").getsource(walls)
        ),
        setup=setup,
        call=call,
    )
    child = subprocess.Popen(
        [sys.executable, "-c", source],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert child.stdout.readline().strip() == "READY", child.stderr.read()
        time.sleep(0.5)
        assert child.poll() is None, "the call ended before the signal"
        os.kill(child.pid, signal.SIGINT)
        out, err = child.communicate(timeout=INTERRUPT_DEADLINE)
    finally:
        if child.poll() is None:
            child.kill()
    assert out.split() == ["INTERRUPTED"], f"stdout {out!r}, stderr {err!r}"
    return out


@pytest.mark.parametrize(
    "setup, call",
    [
        (FALLBACK_GRID, "tracer.trace()"),
        (FALLBACK_GRID, "tracer.trace(progress=lambda done, total: None)"),
        (EVERY_PATH, "tracer.trace_stationary()"),
        (EVERY_PATH, "tracer.stationary_paths([1.0, 1.0], [9.0, 1.1])"),
        (SEARCH, "tracer.search()"),
        (PAIRS, "tracer.solve_pairs(sources, receivers)"),
        (LATE_ROOM, "tracer.search()"),
        (LATE_ROOM, "tracer.impulse_response(rate=8000, duration=0.25)"),
        (LATE_ROOM, "tracer.transmission_loss(frequency=500)"),
        (LONG_RENDER, "tracer.impulse_response(rate=8000, duration=1.25, taps=10001)"),
    ],
    ids=["trace", "trace-progress", "trace_stationary", "stationary_paths", "search", "solve_pairs",
         "search-beams", "impulse_response", "transmission_loss", "rendering"],
)
def test_ctrl_c_raises_keyboard_interrupt(setup, call):
    # Without the signal each call would go on for many seconds and end with FINISHED (or
    # run into the deadline): INTERRUPTED is the stop at work.
    assert interrupt(setup, call).split() == ["INTERRUPTED"]


def test_calls_from_four_threads_at_once_all_succeed():
    n = 40
    scene = walls(
        2,
        [[1.0 + 0.1 * i, 1.0] for i in range(n)],
        [[9.0 - 0.1 * i, 1.1] for i in range(n)],
    )
    tracer = eigenray.Tracer(eigenray.Scene(scene))
    want, one = tracer.trace(), tracer.solve([1.0, 1.0], [9.0, 1.1])
    results, errors = [None] * 8, []

    def run(i):
        try:
            if i % 2 == 0:
                results[i] = tracer.trace()
            else:
                results[i] = tracer.solve([1.0, 1.0], [9.0, 1.1])
        except Exception as e:  # noqa: BLE001 - any failure is the finding
            errors.append(repr(e))

    for _ in range(5):
        threads = [threading.Thread(target=run, args=(i,)) for i in range(8)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        assert errors == []
        for i in range(0, 8, 2):
            np.testing.assert_array_equal(results[i].time, want.time)
        for i in range(1, 8, 2):
            assert (results[i].status, results[i].time) == (one.status, one.time)


def test_updates_wait_for_the_calls_that_read():
    scene = walls(2, [[1.0, 1.0]], [[9.0, 1.1]] * 200)
    tracer = eigenray.Tracer(eigenray.Scene(scene))
    errors = []

    def trace():
        try:
            for _ in range(20):
                tracer.trace()
        except Exception as e:  # noqa: BLE001
            errors.append(repr(e))

    def move():
        try:
            for i in range(50):
                tracer.set_receiver(0, [9.0 - 0.01 * i, 1.1])
        except Exception as e:  # noqa: BLE001
            errors.append(repr(e))

    threads = [threading.Thread(target=f) for f in (trace, trace, move)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert errors == []


def test_complex_numbers_are_a_type_error():
    tracer = eigenray.Tracer(eigenray.Scene(walls(1, [[1.0, 1.0]], [[9.0, 1.1]])))
    z = np.array([[1.0 + 1e-9j, 1.0]])
    with pytest.raises(TypeError, match="complex"):
        tracer.solve_pairs(z, np.array([[9.0, 1.1]]))
    with pytest.raises(TypeError, match="complex"):
        tracer.solve(np.array([1.0 + 0j, 1.0]), [9.0, 1.1])
    with pytest.raises(TypeError, match="complex"):
        tracer.set_receivers(np.array([[9.0 + 0j, 1.1]]))
    with pytest.raises(TypeError, match="complex"):
        tracer.set_interface_points("floor", np.array([[0.0 + 0j, 0.0], [10.0, 0.0]]))


@pytest.mark.parametrize("bad", [5, "yes", 1.5, [True]])
def test_a_progress_that_is_neither_a_bool_nor_callable_is_a_type_error(bad):
    tracer = eigenray.Tracer(eigenray.Scene(walls(1, [[1.0, 1.0]], [[9.0, 1.1]])))
    with pytest.raises(TypeError, match="progress"):
        tracer.trace(progress=bad)


# A child under a 4 GB address-space cap: `SETUP`, then `CALL`, which must raise `ERROR`.
CAPPED = """
import resource, sys
resource.setrlimit(resource.RLIMIT_AS, (4 << 30, 4 << 30))
import numpy as np
import eigenray
{setup}
try:
    {call}
    print("NO ERROR")
except {error} as e:
    print("RAISED", type(e).__name__, e)
"""


def capped(setup, call, error):
    """Runs `call` in a child capped at 4 GB: the line it printed."""
    source = CAPPED.format(setup=setup, call=call, error=error)
    done = subprocess.run(
        [sys.executable, "-c", source], capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 0, f"exit {done.returncode}: {done.stderr[-2000:]}"
    return done.stdout.strip()


SMALL = """
tracer = eigenray.Tracer(eigenray.Scene({
    "media": {"air": {"speed": 1.0}},
    "interfaces": {"mirror": {"points": [[-1e3, 0.0], [1e3, 0.0]]}},
    "sources": [[0.0, 1.0]], "receivers": [[1.0, 1.0]],
    "paths": [{"steps": [{"reflect": "mirror"}], "media": ["air", "air"]}]}))
"""


def test_a_billion_broadcast_pairs_are_a_memory_error():
    out = capped(
        SMALL,
        "tracer.solve_pairs(np.broadcast_to([0., 1.], (10**9, 2)), "
        "np.broadcast_to([1., -1.], (10**9, 2)))",
        "MemoryError",
    )
    assert out.startswith("RAISED MemoryError sources"), out


def test_a_hundred_million_rays_from_a_small_dict_are_a_memory_error():
    setup = """
points = [[float(i), 1.0] for i in range(10**4)]
scene = {"media": {"air": {"speed": 1.0}},
         "interfaces": {"mirror": {"points": [[-1e5, 0.0], [1e5, 0.0]]}},
         "sources": points, "receivers": points,
         "paths": [{"steps": [{"reflect": "mirror"}], "media": ["air", "air"]}]}
tracer = eigenray.Tracer(eigenray.Scene(scene))
"""
    out = capped(setup, "tracer.trace()", "MemoryError")
    assert out.startswith("RAISED MemoryError trace: 100000000 rays"), out
    out = capped(setup, "tracer.trace_stationary()", "MemoryError")
    assert out.startswith("RAISED MemoryError"), out


def test_a_hundred_million_vertices_are_a_memory_error():
    out = capped(
        SMALL,
        "tracer.set_interface_points('mirror', np.broadcast_to([0., 0.], (10**8, 2)))",
        "MemoryError",
    )
    assert out.startswith("RAISED MemoryError interfaces.mirror.points"), out


def test_an_endless_file_stops_at_the_input_limit():
    out = capped("", "eigenray.Scene('/dev/zero')", "eigenray.EigenrayError")
    assert out.startswith("RAISED EigenrayError") and "256 MiB" in out, out


def test_every_stationary_path_reports_its_progress():
    scene = walls(2, [[1.0, 1.0], [1.1, 1.0]], [[9.0, 1.1], [8.9, 1.1]],
                  solver={"stationary": "all"})
    tracer = eigenray.Tracer(eigenray.Scene(scene))
    seen = []
    rays = tracer.trace_stationary(progress=lambda done, total: seen.append((done, total)))
    assert seen and seen[-1] == (4, 4), seen
    assert len(rays.time) >= 4
    with pytest.raises(TypeError, match="progress"):
        tracer.trace_stationary(progress=5)


def test_gradients_of_a_hundred_million_broadcast_rays_are_a_memory_error():
    # Issue 39: a `Rays` state of one ray broadcast to 10^8 rows (little memory) made
    # `gradients()` abort the interpreter while allocating its arrays.
    setup = SMALL + """
_, (state,) = tracer.trace().__reduce__()
n = 10**8
big = {k: np.broadcast_to(v, (n,) + v.shape[1:])
       if isinstance(v, np.ndarray) and v.ndim >= 1 and len(v) == 1 else v
       for k, v in state.items()}
rays = eigenray.Rays._from_state(big)
assert len(rays) == n
"""
    out = capped(setup, "tracer.gradients(rays)", "MemoryError")
    assert out.startswith("RAISED MemoryError gradients: 100000000 rays"), out
