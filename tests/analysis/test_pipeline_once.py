"""Issue 22: each analysis computes its recording's forward kinematics and body parts once and
hands them along; what depends on the model alone is computed when the model is built and
stored with it; the compiled quaternion loops give the readable formulas' values."""

from __future__ import annotations

import io
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from scipy.spatial.transform import Rotation, Slerp

import analysis.clinical.body as body_module
import analysis.clinical.workspace as workspace_module
import analysis.kinematics.forward_kinematics as fk_module
import analysis.landmarks.identification as identification_module
import analysis.landmarks.signature as signature_module
import analysis.pipeline.prepare as prepare_module
import analysis.pipeline.tutor_parts as tutor_parts_module
from analysis.adjustment.affine import adjust
from analysis.bvh import read
from analysis.clinical.body import find_body
from analysis.feedback import Grammar
from analysis.kinematics import kinematics
from analysis.kinematics import quaternions as quat
from analysis.pipeline import analyse, build_model, dump_model, load_model
from analysis.pipeline.tutor_parts import reference_of
from tests.analysis.test_pipeline import landmarks

DATA = Path(__file__).resolve().parents[2] / "data" / "ui-prmd"


@pytest.fixture(scope="module")
def model():
    name = "sessions/m07_s01_correct.bvh.gz"  # an arm exercise: the workspace is measured too
    return build_model(read(DATA / name), *landmarks(name))


def counting(monkeypatch: pytest.MonkeyPatch, module: Any, name: str, calls: list[str]) -> None:
    """Replace ``module.name`` by a wrapper that records each call in ``calls``."""
    original: Callable[..., Any] = getattr(module, name)

    def wrapper(*args: Any, **kwargs: Any) -> Any:
        calls.append(f"{module.__name__}.{name}")
        return original(*args, **kwargs)

    monkeypatch.setattr(module, name, wrapper)


def test_one_kinematics_pass_and_one_body_per_recording(model, monkeypatch):
    calls: list[str] = []
    for module in (prepare_module, body_module, workspace_module, tutor_parts_module):
        for name in ("kinematics", "find_body"):
            if hasattr(module, name):
                counting(monkeypatch, module, name, calls)
    result = analyse(read(DATA / "sessions/m07_s03_incorrect.bvh.gz"), model).to_json()
    assert result["repetitions"] and result["workspace"] and result["clinical_angles"]
    assert sorted(calls) == [
        "analysis.pipeline.prepare.find_body",
        "analysis.pipeline.prepare.kinematics",
    ]


def test_the_key_pose_stages_read_the_pass_they_are_given(model, monkeypatch):
    """No stage computes the recording's rotations or positions a second time behind the
    pipeline's back (there is no memo to hide it): the rotations are read from the frames once,
    by the one `kinematics` pass, and world positions never on their own."""
    upload = read(DATA / "sessions/m07_s03_incorrect.bvh.gz")
    calls: list[str] = []
    for name in ("_rotations", "_positions", "heading_angles", "world"):
        counting(monkeypatch, fk_module, name, calls)
    for module in (signature_module, identification_module):
        counting(monkeypatch, module, "kinematics", calls)
    assert analyse(upload, model).to_json()["landmarks"]
    assert calls == ["analysis.kinematics.forward_kinematics._rotations"]


def test_the_model_stores_what_depends_on_it_alone(model):
    parts = model.tutor_parts
    assert model.rules == Grammar.parse(model.grammar)
    seen = (kinematics(model.tutor), find_body(model.tutor.skeleton))
    fresh = reference_of(model.tutor, model.components.tutor_reps, model.involved_joints, seen)
    assert parts.reference == fresh and parts.reference.involved
    np.testing.assert_array_equal(parts.take.local_q, seen[0].local_q)
    assert parts.take.key_poses.same_as(model.key_poses)
    assert parts.features.shape[1] == 17 and parts.amplitudes.shape == (len(model.joint_names),)
    buffer = io.BytesIO()
    dump_model(model, buffer)
    loaded = load_model(buffer.getvalue())
    assert loaded.rules == model.rules and loaded.tutor_parts.reference == parts.reference


def unit_quaternions(rng: np.random.Generator, shape: tuple[int, ...]) -> np.ndarray:
    q = rng.normal(size=(*shape, 4))
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def as_scipy(q: np.ndarray) -> Rotation:
    return Rotation.from_quat(q.reshape(-1, 4)[:, [1, 2, 3, 0]])  # scipy: (x, y, z, w)


def same_rotation(a: np.ndarray, b: np.ndarray) -> None:
    """Equal up to the sign of the quaternion (q and -q are one rotation)."""
    dots = np.abs(np.sum(a.reshape(-1, 4) * b.reshape(-1, 4), axis=-1))
    np.testing.assert_allclose(dots, 1.0, atol=1e-12)


def test_compiled_quaternion_loops_agree_with_scipy():
    rng = np.random.default_rng(7)
    a, b = unit_quaternions(rng, (50, 6)), unit_quaternions(rng, (50, 6))
    product = (as_scipy(a) * as_scipy(b)).as_quat()[:, [3, 0, 1, 2]]
    same_rotation(quat.multiply(a, b), product)
    v = rng.normal(size=(50, 6, 3))
    np.testing.assert_allclose(
        quat.rotate(a, v).reshape(-1, 3), as_scipy(a).apply(v.reshape(-1, 3)), atol=1e-12
    )
    np.testing.assert_allclose(
        quat.to_matrix(a).reshape(-1, 3, 3), as_scipy(a).as_matrix(), atol=1e-12
    )
    angle = (as_scipy(a).inv() * as_scipy(b)).magnitude()
    np.testing.assert_allclose(quat.angle_between(a, b).ravel(), angle, atol=1e-9)
    # broadcasting as before: one rotation against many
    np.testing.assert_allclose(quat.angle_between(a[:1], a)[0], 0.0, atol=1e-7)


def test_slerp_and_indexed_slerp_agree_with_scipy():
    rng = np.random.default_rng(8)
    keys = unit_quaternions(rng, (2,))
    t = np.linspace(0.0, 1.0, 9)
    expected = Slerp([0.0, 1.0], as_scipy(keys))(t).as_quat()[:, [3, 0, 1, 2]]
    same_rotation(quat.slerp(keys[0], keys[1], t), expected)
    table = unit_quaternions(rng, (5, 3))
    lo, hi = np.array([0, 3, 4, 1]), np.array([1, 4, 4, 2])
    weights = rng.uniform(size=(4, 3))
    np.testing.assert_array_equal(
        quat.slerp_indexed(table, lo, hi, weights), quat.slerp(table[lo], table[hi], weights)
    )


def test_adjusting_only_the_joints_asked_for_changes_no_result():
    rng = np.random.default_rng(9)
    q = quat.make_continuous(unit_quaternions(rng, (1, 4)) + 0.05 * np.cumsum(
        rng.normal(size=(120, 4, 4)), axis=0), axis=0)  # fmt: skip
    q /= np.linalg.norm(q, axis=-1, keepdims=True)
    frames, targets = np.array([10, 60, 100]), unit_quaternions(rng, (3, 4))
    gamma = np.array([0.0, 0.6, 0.0, 1.0])
    out = adjust(q, frames, targets, gamma)
    np.testing.assert_array_equal(out[:, gamma == 0], q[:, gamma == 0])
    for j in np.flatnonzero(gamma):
        alone = adjust(q[:, [j]], frames, targets[:, [j]], gamma[j])
        np.testing.assert_array_equal(out[:, [j]], alone)
    assert not np.allclose(out[:, 1], q[:, 1])


@pytest.mark.parametrize(("shape", "axis"), [((40, 4), 0), ((40, 6, 4), 0), ((3, 40, 5, 4), 1)])
def test_compiled_sign_continuity_gives_the_array_formula_bit_for_bit(shape, axis):
    """`make_continuous` compiled: the signs numpy's formula gives (flips decided on the
    quaternions as given, counted along time), the values untouched otherwise."""
    rng = np.random.default_rng(10)
    q = unit_quaternions(rng, shape[:-1]) * rng.choice([-1.0, 1.0], size=(*shape[:-1], 1))
    moved = np.moveaxis(q.copy(), axis, 0)
    flips = np.sum(moved[1:] * moved[:-1], axis=-1) < 0.0
    moved[1:] *= np.where(np.cumsum(flips, axis=0) % 2 == 1, -1.0, 1.0)[..., None]
    expected = np.moveaxis(moved, 0, axis)
    out = quat.make_continuous(q, axis=axis)
    assert out.shape == q.shape and out.tobytes() == np.ascontiguousarray(expected).tobytes()
    assert np.all(np.sum(np.moveaxis(out, axis, 0)[1:] * np.moveaxis(out, axis, 0)[:-1], -1) >= 0)
