"""
Surgical navigation: track a board in endoscope video and overlay a plan
========================================================================

The course's first use of the camera model: an endoscope, calibrated once (its K and its
strong barrel distortion), films a pattern fixed to the patient; the pattern's pose
[R | t] in every frame places a plan drawn in the pattern's coordinates (a planned cut, a
target) on the live image, through the same camera model, x = K d([R | t] X).

The endoscope here is the simulator's: a 9 x 6 checkerboard (20 mm squares) seen through a
wide lens with barrel distortion (k1 = -0.18), 320 x 240 pixels. A short camera path is
rendered through the whole chain (optics, sensor noise, demosaicing, the camera's
processing) with the true pose of every frame, tracked, and the poses compared with the
truth. Tutorial, with the calibration and the command line (``imageform simulate
--trajectory``, ``imageform track --overlay --plan``): docs/tracking.md.
"""

import math
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from imageform.geometry import BoardTracker, look_at, rvec_to_matrix
from imageform.io import Plan, VideoWriter, open_video
from imageform.report import draw_pose_overlay
from imageform.simulate import Trajectory, board_poses, load_scene, render_frames

scene = load_scene(
    {
        "name": "endoscope and board",
        "render": {"width": 320, "height": 240, "supersampling": 1},
        "illuminant": {"type": "daylight", "temperature_K": 5500.0},
        "camera": {
            "fx_px": 280.0, "fy_px": 277.5, "cx_px": 161.0, "cy_px": 118.0,
            "eye_m": [0.0, -0.22, 0.03], "target_m": [0.0, 0.0, 0.0],
            "distortion": {"k1": -0.18, "k2": 0.03},
        },
        "lens": {"defocus": False, "vignetting": "none"},
        "processing": {"demosaic": "malvar", "white_balance": "gray_world",
                       "color_correction": "none", "lens_shading_correction": False},
        "objects": [
            {"type": "checkerboard", "center_m": [0.0, 0.0, 0.0], "squares": [10, 7],
             "square_size_m": 0.02},
        ],
    }
)  # fmt: skip
camera = scene.camera  # what `imageform simulate` writes as camera.toml: K and distortion
print(np.round(np.asarray(camera.K), 1), camera.distortion, sep="\n")

# %%
# The camera path: one second at 16 frames per second, the endoscope swinging across the
# board (z up in the scene). Each frame is a whole simulation; ``board_poses`` gives the
# true pose of the board in each frame's camera, in millimetres, with the origin at its
# first inner corner, as the tracker reports it.

fps, n = 16.0, 16
times = np.arange(n) / fps
R, t = [], []
for s in times:
    a = math.pi * s / times[-1]
    pose = look_at([0.05 * math.cos(a), -0.22, 0.03 * math.sin(a)], [0, 0, 0], [0, 0, 1])
    R.append(np.asarray(pose.R))
    t.append(np.asarray(pose.t))
path = Trajectory(times, np.array(R), np.array(t))
board, truth = board_poses(scene, path)
work = Path(tempfile.mkdtemp())
with VideoWriter(work / "clip.mp4", fps=fps) as video:
    for frame in render_frames(scene, path, rng=1):
        video.write(frame)
print(f"{board}: {n} frames, the board {np.linalg.norm(truth[0][1]):.0f} mm away")

# %%
# Track every frame of the decoded video and draw the plan, given in the board's
# millimetres: a planned cut across the board (a polyline, partly 10 mm below its surface)
# and a target 30 mm beneath it. The board's x, y and z axes and the corners found are
# drawn too; everything goes through the lens's distortion, so straight lines bend.

plan = Plan(
    np.array([[20.0, 20, 0], [80, 40, 0], [140, 40, 10], [80, 50, 30]]),
    polylines=(np.array([0, 1, 2]),),
    singles=np.array([3]),
)
tracker = BoardTracker((9, 6), camera.K, camera.distortion, square=20.0)
poses, overlay = [], []
with open_video(work / "clip.mp4") as video:
    for frame in video:
        pose = tracker.update(frame.image)
        poses.append(pose)
        label = f"{frame.index}: rms {pose.rms_px:.2f} px"  # the reprojection error
        overlay.append(
            draw_pose_overlay(
                frame.image, pose, camera.K, camera.distortion, plan=plan, label=label
            )
        )

fig, axes = plt.subplots(1, 3, figsize=(11, 3))
for ax, i in zip(axes, (0, n // 2, n - 1), strict=True):
    ax.imshow(overlay[i])
    ax.set_title(f"frame {i} ({poses[i].searched})")
    ax.axis("off")
fig.tight_layout()
plt.show()

# %%
# Against the truth: the translation error as a share of the distance, the rotation error,
# and the jitter, the change of the translation error from one frame to the next (how much
# the overlay shakes on the screen). The dotted lines are the accuracy the course's
# navigation system asks for (issue 27: 0.5 % and 0.3 degrees, median).

t_err, r_err = [], []
for pose, (Rt, tt) in zip(poses, truth, strict=True):
    t_err.append(100 * np.linalg.norm(pose.tvec - tt) / np.linalg.norm(tt))
    dR = np.asarray(rvec_to_matrix(pose.rvec)) @ Rt.T
    r_err.append(math.degrees(math.acos(np.clip((np.trace(dR) - 1) / 2, -1, 1))))
t_err, r_err = np.array(t_err), np.array(r_err)
jitter = np.abs(np.diff(t_err))
print(
    f"board found in {sum(p.found for p in poses)} of {n} frames; median errors: translation "
    f"{np.nanmedian(t_err):.3f} % of the distance, rotation {np.nanmedian(r_err):.3f} deg; "
    f"jitter {np.nanmedian(jitter):.4f} % of the distance"
)
fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 3.2))
a1.plot(t_err, "o-", ms=3, label="error")
a1.plot(np.arange(1, n), jitter, "s-", ms=3, label="jitter (change from the last frame)")
a1.axhline(0.5, color="k", lw=0.8, ls=":")
a1.set_xlabel("frame")
a1.set_ylabel("% of the distance")
a1.set_title("translation")
a1.legend(fontsize=8)
a2.plot(r_err, "o-", ms=3)
a2.axhline(0.3, color="k", lw=0.8, ls=":")
a2.set_xlabel("frame")
a2.set_ylabel("degrees")
a2.set_title("rotation")
fig.tight_layout()
plt.show()
