"""How well the frames fix a self-calibrated focal length, and the lens chosen on few frames.

``Reconstruction.focal_sd_px``: the profile of the final adjustment's cost in f, widened by
what a restart from another camera moved it and, where two lenses both fix f, by their
difference (``sfm._with_spread``); a focal length with a standard deviation over 10 % is
said not fixed (``benchmarks/results/sfm-model-choice-2026-12-01e.md``).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from imageform.geometry import look_at, reconstruct_sequence
from tests import sfm_scenes

pytest.importorskip("cv2")


def _frames(poses: list, w: int = 320, h: int = 240) -> tuple[list, np.ndarray, np.ndarray]:
    """The room through a pinhole of f 250 px at 320 px wide; COLMAP's guess 1.2 w."""
    f = 250.0 * w / 320
    K = np.array([[f, 0, (w - 1) / 2], [0, f, (h - 1) / 2], [0, 0, 1]])
    rng = np.random.default_rng(5)
    frames = [sfm_scenes.render(K, p, (w, h), noise=1.5, rng=rng) for p in poses]
    K0 = K.copy()
    K0[0, 0] = K0[1, 1] = 1.2 * w
    return frames, K, K0


def _translated(n: int) -> list:
    """A camera that moves forward and aside without turning: f is not in the images."""
    out = []
    for i in range(n):
        eye = np.array([2.0 + 0.12 * i, 1.0 + 0.25 * i, 1.4 + 0.03 * i])
        pose = look_at(eye, eye + np.array([0.0, 2.0, -0.2]), up=(0.0, 0.0, 1.0))
        out.append((np.asarray(pose.R, np.float64), np.asarray(pose.t, np.float64)))
    return out


def test_a_walk_that_turns_fixes_f() -> None:
    """8 frames of the walk (it turns 100 degrees): f 250 px found within 1 % from 384 px,
    its standard deviation under 2 % (measured 249.9 +- 1.1 px), no note."""
    frames, _, K0 = _frames(sfm_scenes.poses(8))
    rec = reconstruct_sequence(frames, K0, refine_focal=True, refine_distortion=True)
    assert rec.registered.all(), rec.notes
    assert rec.K is not None and rec.K[0, 0] == pytest.approx(250.0, rel=0.01)
    assert rec.focal_sd_px is not None and rec.focal_sd_px < 0.02 * rec.K[0, 0]
    assert abs(rec.K[0, 0] - 250.0) < 4 * rec.focal_sd_px + 0.5
    assert not any(n.startswith("the focal length is not fixed") for n in rec.notes)


def test_translation_alone_leaves_f_not_fixed() -> None:
    """6 frames of a camera that moves without turning: scaling f, the points' and the
    translations' sideways parts together changes no image (f is not in the data). The
    restarts wander (384 -> 421 -> 497 -> 522 px for 250), the profile is wide: f +- 25 %,
    said not fixed, where the code before returned 522 px without a word of doubt."""
    frames, _, K0 = _frames(_translated(6))
    rec = reconstruct_sequence(frames, K0, refine_focal=True, refine_distortion=True)
    assert rec.K is not None and rec.focal_sd_px is not None
    assert rec.focal_sd_px > 0.1 * rec.K[0, 0], rec.notes
    note = next(n for n in rec.notes if n.startswith("the focal length is not fixed"))
    assert f"f = {rec.K[0, 0]:.1f} px +- {rec.focal_sd_px:.1f} px" in note, note


def _model(f: float, sd: float | None, fisheye: bool = False, reg: int = 13) -> Any:
    from imageform.geometry import KannalaBrandt
    from imageform.geometry.sfm import Reconstruction

    n = 13
    R, t = np.full((n, 3, 3), np.nan), np.full((n, 3), np.nan)
    R[:reg], t[:reg] = np.eye(3), 0.0
    K = np.array([[f, 0, 99.5], [0, f, 99.5], [0, 0, 1]])
    return Reconstruction(
        R, t, np.arange(n) < reg, np.zeros((0, 3)), np.zeros((0, 3), np.uint8),
        np.zeros(0, np.int64), np.zeros(n), [], np.full(9, 0.5), K=K,
        distortion=KannalaBrandt() if fisheye else None, focal_sd_px=sd,
    )  # fmt: skip


def _script(monkeypatch: pytest.MonkeyPatch, pinhole: Any, fish: Any, costs: dict) -> list:
    """SIMPLE_RADIAL's model (its term held: k1 0) and the fisheye's, no SfM run; the
    tracks' cost of each by its f (100 views)."""
    from imageform.geometry import KannalaBrandt, sfm

    calls: list[str] = []

    def one_model(images: Any, K: Any, distortion: Any, kw: dict) -> Any:
        calls.append("fisheye" if isinstance(distortion, KannalaBrandt) else "pinhole")
        return fish if calls[-1] == "fisheye" else pinhole

    monkeypatch.setattr(sfm, "_one_model", one_model)
    monkeypatch.setattr(sfm, "_tracks_of", lambda cache, rec: (np.zeros(0, np.int64),) * 3)
    monkeypatch.setattr(sfm, "_track_cost", lambda rec, f, t: (costs[float(rec.K[0, 0])], 100))
    return calls


def test_a_lens_that_fixes_f_beats_one_that_does_not(monkeypatch: pytest.MonkeyPatch) -> None:
    """C3VD's 13 frames, seed 1: SIMPLE_RADIAL's f 323.8 px, its profile flat (inf), the
    fisheye's 207.7 +- 8.1 px: the fisheye is tried (SIMPLE_RADIAL's f not fixed) and kept
    though its tracks cost more (1550 against 1349 px^2); it is said why. Both fixed: the
    cost decides, and the f kept is widened by half their difference (a model average's
    between-model spread). Neither fixed: the cost decides, and a note says f is not."""
    K = np.array([[537.6, 0, 99.5], [0, 537.6, 99.5], [0, 0, 1]])
    frames = [np.zeros((200, 200), np.uint8)] * 13
    costs = {323.8: 1349.0, 207.7: 1550.0}
    calls = _script(monkeypatch, _model(323.8, np.inf), _model(207.7, 8.1, True), costs)
    rec = reconstruct_sequence(frames, K, refine_focal=True, refine_distortion=True)
    assert "fisheye" in calls
    assert rec.K is not None and rec.K[0, 0] == 207.7 and rec.focal_sd_px == 8.1
    note = next(n for n in rec.notes if n.startswith("the fisheye tried"))
    assert "SIMPLE_RADIAL's f = 323.8 px +- inf px" in note, note
    assert note.endswith("kept (the fisheye, its f fixed by the frames)"), note
    assert not any(n.startswith("the focal length is not fixed") for n in rec.notes)
    # both fixed (colon-a's 8 frames: 135.5 +- 6.7 and 92.9 +- 2.9 px): the cost decides,
    # the two f weighed alike widen the one kept: sqrt(2.9^2 + 21.3^2) = 21.5 px, not fixed
    costs = {135.5: 768.0, 92.9: 599.0}
    _script(monkeypatch, _model(135.5, 6.7), _model(92.9, 2.9, True), costs)
    rec = reconstruct_sequence(frames, K, refine_focal=True, refine_distortion=True)
    assert rec.K is not None and rec.K[0, 0] == 92.9
    assert rec.focal_sd_px == pytest.approx(np.hypot(2.9, (135.5 - 92.9) / 2))
    assert any(n.startswith("the focal length is not fixed") for n in rec.notes), rec.notes
    # neither fixed: the cost (the pinhole's lower) decides, said not fixed
    costs = {836.6: 375.0, 129.6: 1124.0}
    _script(monkeypatch, _model(836.6, np.inf), _model(129.6, np.inf, True), costs)
    rec = reconstruct_sequence(frames, K, refine_focal=True, refine_distortion=True)
    assert rec.K is not None and rec.K[0, 0] == 836.6 and rec.focal_sd_px == np.inf
    note = next(n for n in rec.notes if n.startswith("the focal length is not fixed"))
    assert "f = 836.6 px +- inf px" in note, note
    # the fixed lens registers fewer frames: not kept for its f
    _script(monkeypatch, _model(323.8, np.inf), _model(207.7, 8.1, True, reg=12), costs)
    costs.update({323.8: 1349.0, 207.7: 1550.0})
    rec = reconstruct_sequence(frames, K, refine_focal=True, refine_distortion=True)
    assert rec.K is not None and rec.K[0, 0] == 323.8


def test_a_fixed_f_without_a_fisheye_sign_tries_no_fisheye(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Temple's 13 frames: SIMPLE_RADIAL's f 1543.0 +- 12.4 px, no term: nothing else is
    tried, no note; a given K held (no refine_focal): no standard deviation."""
    K = np.array([[768.0, 0, 99.5], [0, 768.0, 99.5], [0, 0, 1]])
    frames = [np.zeros((200, 200), np.uint8)] * 13
    calls = _script(monkeypatch, _model(1543.0, 12.4), _model(300.0, 1.0, True), {})
    rec = reconstruct_sequence(frames, K, refine_focal=True, refine_distortion=True)
    assert "fisheye" not in calls and rec.focal_sd_px == 12.4
    assert not any("focal length is not fixed" in n for n in rec.notes)


def _restarts(monkeypatch: pytest.MonkeyPatch, models: list) -> list:
    """``_one_model`` returns ``models`` in turn (the first run, then each restart)."""
    from imageform.geometry import sfm

    calls: list[float] = []

    def one_model(images: Any, K: Any, distortion: Any, kw: dict) -> Any:
        calls.append(float(np.asarray(K)[0, 0]))
        return models[len(calls) - 1]

    monkeypatch.setattr(sfm, "_one_model", one_model)
    return calls


def test_a_restart_that_still_moves_f_is_said_in_the_one_verdict(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """KITTI's 13 frames (sfm-model-choice-2026-12-01e.md, held out): the last restart still
    moved f by more than 5 % and a note said the camera "did not settle" and that the frames
    do not fix it, while its standard deviation (that move one of its terms) said f fixed
    (9 %). Now the move is said within the one verdict, the same as ``focal_fixed``'s.
    Scripted: 1000 -> 800 -> 700 -> 640 px, the profile 30 px: sqrt(30^2 + 60^2 / 2) =
    52.0 px (8 %), fixed; ending at 600 px: 76.8 px (13 %), not fixed."""
    K = np.array([[1000.0, 0, 99.5], [0, 1000.0, 99.5], [0, 0, 1]])
    frames = [np.zeros((200, 200), np.uint8)] * 13
    for last, fixed in ((640.0, True), (600.0, False)):
        models = [_model(800.0, 30.0), _model(700.0, 30.0), _model(last, 30.0)]
        calls = _restarts(monkeypatch, models)
        rec = reconstruct_sequence(frames, K, refine_focal=True)
        assert calls == [1000.0, 800.0, 700.0]  # the reconstruction itself: as before
        assert rec.K is not None and rec.K[0, 0] == last and rec.focal_sd_px is not None
        assert rec.focal_sd_px == pytest.approx(np.hypot(30.0, (700.0 - last) / np.sqrt(2)))
        assert (rec.focal_sd_px <= 0.1 * last) is fixed
        assert not any("did not settle" in n or "do not fix" in n for n in rec.notes), rec.notes
        verdicts = [n for n in rec.notes if n.startswith("the focal length is")]
        assert len(verdicts) == 1, rec.notes
        moved = f"the last restart still moved f from 700.0 to {last:.1f} px"
        assert moved in verdicts[0], verdicts
        assert verdicts[0].startswith(
            "the focal length is fixed" if fixed else "the focal length is not fixed"
        ), verdicts
        assert not any(n.startswith("the last restart") for n in rec.notes), rec.notes


def test_a_lens_that_does_not_settle_says_so_apart_from_f(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """k1 still moving after the two restarts (-0.6 -> -1.2 -> -1.8, f 1000 px throughout,
    fixed): a note says the lens did not settle, nothing says f is not fixed."""
    from dataclasses import replace

    from imageform.geometry import BrownConrady

    K = np.array([[1000.0, 0, 99.5], [0, 1000.0, 99.5], [0, 0, 1]])
    frames = [np.zeros((200, 200), np.uint8)] * 13
    models = [
        replace(_model(1000.0, 10.0), distortion=BrownConrady(k1=k1)) for k1 in (-0.6, -1.2, -1.8)
    ]
    _restarts(monkeypatch, models)
    rec = reconstruct_sequence(frames, K, refine_focal=True, refine_distortion=True)
    assert rec.K is not None and rec.K[0, 0] == 1000.0 and rec.focal_sd_px == 10.0
    note = next(n for n in rec.notes if n.startswith("the lens did not settle"))
    assert "k1 from -1.200 to -1.800" in note and "f " not in note, note
    assert not any(n.startswith("the focal length is") for n in rec.notes), rec.notes
