"""Pickling, for `multiprocessing`, `concurrent.futures`, joblib, Dask and Ray: a `Scene` and a
`Tracer` travel as the scene's JSON document (edits included) and trace the same rays bit for
bit; a `Rays` travels as its arrays and names, every attribute equal; a transmission-loss map
computed in receiver blocks by worker processes equals the one computed in one process."""

import concurrent.futures
import copy
import json
import multiprocessing
import pickle

import numpy as np
import pytest

import eigenray

# A speed whose slowness does not give it back: 1 / (1 / 1471.5) != 1471.5.
SPEED = 1471.5
assert 1 / (1 / SPEED) != SPEED

# Lloyd's mirror: a point source under a pressure-release surface, the direct and the
# surface-reflected arrivals (a search of one step).
FREQUENCY, DEPTH = 150.0, 25.0


def lloyd(receivers):
    return {
        "media": {"water": {"speed": 1500.0}},
        "background": "water",
        "interfaces": {
            "surface": {"points": [[-10, 0], [1100, 0]], "reflection": "pressure-release"},
        },
        "sources": [[0.0, -DEPTH]],
        "receivers": np.asarray(receivers).tolist(),
        "search": {"max_steps": 1, "refract": False},
        "amplitudes": {"source": "point", "frequency": FREQUENCY},
    }


def lloyd_receivers(n):
    """`n` receivers over 1 km of range and 80 m of depth, not on a grid."""
    rng = np.random.default_rng(32)
    return np.column_stack([rng.uniform(5, 1000, n), -rng.uniform(1, 80, n)])


# Paths with every kind of answer: a direct ray that a screen obstructs for some receivers
# (an amplitude without a value), a surface echo that misses the short surface for others
# (no path, with a reason), and an echo off a two-segment bottom.
PATHS = {
    "media": {"water": {"speed": SPEED, "density": 1000.0, "attenuation": 0.01},
              "mud": {"speed": 1700.0, "density": 1800.0}},
    "interfaces": {
        "surface": {"points": [[-5, 0], [30, 0]], "reflection": "pressure-release"},
        "screen": {"points": [[20, -12], [20, -4]], "reflection": {"absorption": 0.3}},
        "bottom": {"points": [[-5, -30], [25, -32], [60, -29]]},
    },
    "sources": [[0.0, -10.0]],
    "receivers": [[x, -8.0] for x in np.linspace(5, 55, 11)],
    "paths": [
        {"name": "direct", "steps": [], "media": ["water"]},
        {"name": "surface", "steps": [{"reflect": "surface"}], "media": ["water", "water"]},
        {"name": "bottom", "steps": [{"reflect": "bottom"}], "media": ["water", "water"]},
    ],
    "amplitudes": {"source": "point", "frequency": 500},
}


def attributes(rays):
    """Every public attribute of `rays` (its arrays, lists and names)."""
    names = [n for n in dir(rays) if not n.startswith("_")]
    return {n: getattr(rays, n) for n in names if not callable(getattr(rays, n))}


def assert_same_rays(a, b):
    """Every attribute equal: arrays of the same dtype and shape, equal with NaN equal to NaN;
    everything else equal."""
    got, expected = attributes(a), attributes(b)
    assert got.keys() == expected.keys()
    for name, want in expected.items():
        have = got[name]
        if isinstance(want, np.ndarray):
            assert isinstance(have, np.ndarray), name
            assert have.dtype == want.dtype and have.shape == want.shape, name
            nan = want.dtype.kind in "fc"
            assert np.array_equal(have, want, equal_nan=nan), name
        else:
            assert have == want, name
    assert len(a) == len(b)


def round_trip(value):
    return pickle.loads(pickle.dumps(value, protocol=pickle.HIGHEST_PROTOCOL))


def test_a_scene_reads_back_bit_for_bit():
    scene = eigenray.Scene(PATHS)
    again = round_trip(scene)
    assert isinstance(again, eigenray.Scene)
    assert again.to_json() == scene.to_json()
    assert np.array_equal(again.slowness, scene.slowness)
    assert json.loads(scene.to_json())["media"]["water"]["speed"] == SPEED
    assert_same_rays(eigenray.Tracer(again).trace(), eigenray.Tracer(scene).trace())
    # With every protocol, and through copy.
    for protocol in range(pickle.HIGHEST_PROTOCOL + 1):
        assert pickle.loads(pickle.dumps(scene, protocol)).to_json() == scene.to_json()
    assert copy.deepcopy(scene).to_json() == scene.to_json()


def test_a_tracer_reads_back_with_its_edits():
    tracer = eigenray.Tracer(eigenray.Scene(PATHS))
    receivers = np.column_stack([np.linspace(3, 50, 11), np.linspace(-25, -2, 11)])
    tracer.set_receivers(receivers)
    tracer.set_medium_speed("water", 1 / 7e-4)
    tracer.set_source(0, [1.0, -12.5])
    tracer.set_interface_points("bottom", [[-5, -30], [20, -33], [40, -31.5], [60, -29]])
    again = round_trip(tracer)
    assert isinstance(again, eigenray.Tracer)
    assert np.array_equal(again.scene.receivers, receivers)
    assert again.scene.to_json() == tracer.scene.to_json()
    assert_same_rays(again.trace(), tracer.trace())
    assert_same_rays(again.trace_stationary(), tracer.trace_stationary())
    # A tracer built afresh from the edited scene gives the same rays, too.
    fresh = eigenray.Tracer(eigenray.Scene(json.loads(tracer.scene.to_json())))
    assert_same_rays(fresh.trace(), tracer.trace())


def test_rays_read_back_every_attribute():
    tracer = eigenray.Tracer(eigenray.Scene(PATHS))
    rays = tracer.trace()
    statuses = {rays.status_names[s] for s in rays.status}
    assert {"converged", "obstructed", "no_path"} <= statuses
    assert any(r is not None for r in rays.reason)
    assert any(r is not None for r in rays.amplitude_reason)
    again = round_trip(rays)
    assert isinstance(again, eigenray.Rays)
    assert_same_rays(again, rays)
    assert again.amplitude.dtype == np.complex128
    # The unpickled rays serve as the `out` of the next trace, and for gradients.
    assert_same_rays(tracer.trace(out=again), rays)
    grads = tracer.gradients(round_trip(rays))
    assert np.array_equal(grads.source, tracer.gradients(rays).source, equal_nan=True)


def test_rays_of_every_stationary_path_and_of_pairs_read_back():
    tracer = eigenray.Tracer(eigenray.Scene(PATHS))
    stationary = tracer.trace_stationary()
    assert stationary.arrival is not None and stationary.kink is not None
    assert_same_rays(round_trip(stationary), stationary)
    pairs = tracer.solve_pairs([[0, -10], [1, -11]], [[12, -3], [50, -20]], path="bottom")
    assert_same_rays(round_trip(pairs), pairs)
    # Without amplitudes.
    plain = dict(PATHS)
    del plain["amplitudes"]
    rays = eigenray.Tracer(eigenray.Scene(plain)).trace()
    assert rays.amplitude is None
    assert_same_rays(round_trip(rays), rays)


def test_a_bad_state_is_refused():
    rays = eigenray.Tracer(eigenray.Scene(PATHS)).trace()
    _, (state,) = rays.__reduce__()
    assert len(state["reason_rows"]) > 0
    bad_states = {
        "do not fit": dict(state, time=state["time"][:-1]),
        "`source` has 32 entries for 33 rays": dict(state, source=state["source"][1:]),
        "`status`": dict(state, status=state["status"].astype(np.int64)),
        "bad `reason` codes": dict(state, reason_codes=np.full_like(state["reason_codes"], 99)),
        "no `path_names`": {k: v for k, v in state.items() if k != "path_names"},
    }
    for message, bad in bad_states.items():
        with pytest.raises(ValueError, match=message):
            eigenray.Rays._from_state(bad)


def transmission_loss_block(tracer, block):
    """One worker's share: the pickled tracer, moved to a block of receivers."""
    tracer.set_receivers(block)
    return tracer.transmission_loss()


def test_a_tl_map_in_receiver_blocks_on_worker_processes_is_bit_for_bit():
    blocks, size = 6, 250
    receivers = lloyd_receivers(blocks * size)
    whole = eigenray.Tracer(eigenray.Scene(lloyd(receivers))).transmission_loss()
    assert whole.shape == (1, blocks * size) and np.isfinite(whole).all()

    # One tracer of a block's size, shipped (pickled) to the workers with each block.
    tracer = eigenray.Tracer(eigenray.Scene(lloyd(receivers[:size])))
    context = multiprocessing.get_context("spawn")
    with concurrent.futures.ProcessPoolExecutor(2, mp_context=context) as pool:
        parts = pool.map(
            transmission_loss_block,
            [tracer] * blocks,
            np.split(receivers, blocks),
        )
        tl = np.concatenate(list(parts), axis=1)
    assert tl.dtype == whole.dtype
    assert np.array_equal(tl, whole)


def test_rays_of_a_fortran_ordered_state_are_refused_as_out_and_left_as_they_were():
    # Issue 39: a `Rays` read from a state whose `points` are in Fortran order served as the
    # `out` of `trace` and had its rows written in C order (zeros in row 0).
    tracer = eigenray.Tracer(eigenray.Scene(PATHS))
    rays = tracer.trace()
    _, (state,) = rays.__reduce__()
    fortran = eigenray.Rays._from_state(dict(state, points=np.asfortranarray(state["points"])))
    assert not fortran.points.flags.c_contiguous
    before = {k: np.copy(v) if isinstance(v, np.ndarray) else v
              for k, v in attributes(fortran).items()}
    with pytest.raises(eigenray.EigenrayError, match="C-contiguous") as caught:
        tracer.trace(out=fortran)
    assert caught.value.key == "out"
    after = attributes(fortran)
    for name, want in before.items():
        if isinstance(want, np.ndarray):
            assert np.array_equal(after[name], want, equal_nan=want.dtype.kind in "fc"), name
        else:
            assert after[name] == want, name
    # Read in any order, its points are the rays' own: their gradients are the same.
    assert np.array_equal(
        tracer.gradients(fortran).vertex_d, tracer.gradients(rays).vertex_d, equal_nan=True
    )
    # The same state in C order is written in place, as the fresh rays.
    again = eigenray.Rays._from_state(dict(state, points=np.ascontiguousarray(state["points"])))
    assert_same_rays(tracer.trace(out=again), rays)
