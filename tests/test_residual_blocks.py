"""Every registered residual block: analytic Jacobian against central finite differences through
the parameter blocks' retractions (so a new measurement kind cannot land with a wrong derivative),
and the checker itself catches wrong derivatives."""

import numpy as np
import pytest

import robocal.calib  # noqa: F401  (imports and so registers every residual block of the library)
import robocal.tcp  # noqa: F401  (the tool-calibration layer may add blocks too)
from robocal.calib.blocks import VectorBlock
from robocal.calib.residuals import RESIDUAL_BLOCKS, ResidualBlock, jacobian_errors, perturbed_values

TOL = 1e-6  # |fd - J| relative to the largest derivative of the block's rows


def _examples(cls, seed):
    ex = cls.example(np.random.default_rng(seed))
    return ex if isinstance(ex, (list, tuple)) else [ex]


def test_the_library_registers_its_residual_kinds():
    kinds = {cls.kind for cls in RESIDUAL_BLOCKS.values()}
    assert {"point", "rotation", "distance", "plane", "prior", "fixed_point"} <= kinds


COLLECTED = sorted(RESIDUAL_BLOCKS)


def _check_block_class(key):
    cls = RESIDUAL_BLOCKS[key]
    if cls.example.__func__ is ResidualBlock.example.__func__:
        pytest.fail(f"{key} is registered but has no example() factory: the finite-difference test cannot "
                    "check its Jacobian (add a small seeded example, or register=False for test doubles)")
    for seed in (0, 1):
        for i, res in enumerate(_examples(cls, seed)):
            assert isinstance(res, cls)
            assert res.n_rows > 0, f"{key} example {i}: no rows"
            values = perturbed_values(res, np.random.default_rng(100 + seed))
            errors = jacobian_errors(res, values)
            assert set(errors) == {b.name for b in res.parameter_blocks}
            bad = {b: e for b, e in errors.items() if not e < TOL}
            assert not bad, f"{key} example {i} (seed {seed}): Jacobian differs from finite differences: {bad}"


@pytest.mark.parametrize("key", COLLECTED)
def test_every_registered_residual_block_has_a_correct_analytic_jacobian(key):
    _check_block_class(key)


def test_blocks_registered_after_collection_are_checked_too():
    """Classes registered after this module was collected (by other test modules, plugins)."""
    late = sorted(set(RESIDUAL_BLOCKS) - set(COLLECTED))
    for key in late:
        _check_block_class(key)


def test_examples_are_seeded():
    for key, cls in RESIDUAL_BLOCKS.items():
        a, b = _examples(cls, 3), _examples(cls, 3)
        for ra, rb in zip(a, b):
            va, vb = perturbed_values(ra), perturbed_values(rb)
            for xa, xb in zip(va.values(), vb.values()):
                assert np.array_equal(xa, xb), key


class _WrongSign(ResidualBlock, register=False):
    """A deliberately wrong block: r = p - 1 with the Jacobian of r instead of -dr/dp."""

    kind = "wrong"

    def __init__(self, block):
        super().__init__((block,), np.zeros(3, int))
        self.block = block

    def evaluate(self, ev, jacobian):
        r = ev[self.block] - 1.0
        return r, ({self.block: np.eye(3)} if jacobian else None)


class _WrongShape(_WrongSign, register=False):
    def evaluate(self, ev, jacobian):
        r, _ = super().evaluate(ev, jacobian)
        return r, ({self.block: np.eye(3)[:2]} if jacobian else None)


def test_the_checker_catches_a_wrong_derivative_and_a_wrong_shape():
    blk = VectorBlock("p", ["p.x", "p.y", "p.z"], ["mm"] * 3, [1.0, 2.0, 3.0])
    assert jacobian_errors(_WrongSign(blk))["p"] == pytest.approx(2.0)  # -I expected, +I given
    with pytest.raises(AssertionError, match="shape"):
        jacobian_errors(_WrongShape(blk))
    assert "_WrongSign" not in " ".join(RESIDUAL_BLOCKS)
