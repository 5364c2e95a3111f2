"""The amplitudes of reflect-only paths in one medium (the unfolded tube's closed form) against
an independent 50-digit image-method reference (`benches/unfolded_reference.py`, mpmath): the
spreading to round-off, the amplitude to the coefficient's error (the coefficient reads the
solved points' angles of incidence; the closed form does not touch it)."""

import importlib.util

import pytest

pytest.importorskip("mpmath")


def reference_module(root):
    spec = importlib.util.spec_from_file_location(
        "unfolded_reference", root / "benches" / "unfolded_reference.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


# Scene, the number of such paths, the largest relative error allowed on the spreading. The
# waveguide's axisymmetric width reads the first leg's solved direction (its error ~1e-13);
# the sweep this closed form replaced was off by 1.6e-10 there and by 1.6e-13 in the
# 30-order room.
CASES = [
    ("examples/scenes/comb_room.json", 45, 2e-15),
    ("examples/scenes/room_orders.json", 1776, 4e-15),
    ("examples/scenes/shallow_water.json", 156, 4e-15),
    ("fixtures/amplitudes/room_search.json", 19, 2e-15),
    ("fixtures/amplitudes/waveguide.json", 14, 2e-12),
]


@pytest.mark.parametrize("scene,paths,bound", CASES, ids=[c[0] for c in CASES])
def test_reflect_only_amplitudes_are_the_image_methods(cli, root, scene, paths, bound):
    reference = reference_module(root)
    count, worst = reference.worst_errors(str(root / scene), cli)
    amplitude, spreading, attenuation, coefficient = worst
    assert count == paths
    assert spreading <= bound
    assert attenuation <= 1e-15
    assert amplitude <= coefficient + 2 * bound
