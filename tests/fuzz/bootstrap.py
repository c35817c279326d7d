"""Draft valid calls for public callables missing from the table (a maintainer's tool).

``PYTHONPATH=src python -m tests.fuzz.bootstrap [--all] > draft.py`` guesses a valid call
for each callable without an entry in :data:`tests.fuzz.table.VALID` from its parameter
names (``image`` -> ``V("rgb")``, ``K`` -> ``V("K")`` ...) and defaults, tries it (5 s
alarm), and prints a table entry: a ``call(...)`` that worked, or a ``Skip`` with the
error of the best guess to finish by hand.
"""

from __future__ import annotations

import inspect
import itertools
import signal
import sys
import warnings
from typing import Any

from tests.fuzz.runner import C, Skip, public_callables
from tests.fuzz.values import resolve

#: Candidate argument sources by parameter name (the first that works is kept).
GUESS: dict[str, list[str]] = {
    "image": ['V("rgb")', 'V("gray")', 'V("rgb_big")'],
    "img": ['V("rgb")'],
    "display": ['V("rgb")'],
    "reference": ['V("rgb")', "1"],
    "target": ['V("rgb")', 'V("spectrum")'],
    "source": ['V("rgb")'],
    "rgb": ['V("rgb4")', 'V("rgb")'],
    "linear_srgb": ['V("rgb")'],
    "values": ['V("rgb4")', 'V("rgb")'],
    "gray": ['V("gray")'],
    "raw": ['V("gray")'],
    "xyz": ['V("xyz")'],
    "xyy": ['V("xyz")'],
    "lab": ['V("lab")'],
    "lab1": ['V("lab")'],
    "lab2": ['V("lab")'],
    "lch": ['V("lab")'],
    "luv": ['V("lab")'],
    "hsv": ['V("rgb4")'],
    "hsl": ['V("rgb4")'],
    "hsi": ['V("rgb4")'],
    "cmy": ['V("rgb4")'],
    "cmyk": ["np.full((4, 4), 0.25)"],
    "ycbcr": ['V("rgb")'],
    "luma": ['V("gray")'],
    "xy": ['V("xy")'],
    "uv": ['V("uv")', 'V("xy")'],
    "cct": ["5000.0", "np.array([4000.0, 6500.0])"],
    "temperature": ["5000.0"],
    "temperatures": ["np.array([3000.0, 5000.0])"],
    "h1": ["np.array([10.0, 200.0])"],
    "h2": ["np.array([350.0, 20.0])"],
    "hue": ["np.array([10.0, 200.0])"],
    "K": ['V("K")'],
    "R": ['V("R")'],
    "t": ['V("t")'],
    "H": ['V("H")'],
    "P": ['V("P")'],
    "rvec": ['V("rvec")'],
    "points": ['V("points3")', 'V("points2")', 'V("uv")'],
    "object_points": ['V("points3")'],
    "image_points": ['V("uv")'],
    "vertices": ["np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])"],
    "depth": ['V("depth")', "4.0"],
    "lines": ['V("lines")'],
    "camera": ['V("camera")'],
    "sensor": ['V("sensor")'],
    "spectrum": ['V("spectrum")'],
    "s1": ['V("spectrum")'],
    "s2": ['V("spectrum")'],
    "wavelengths": ['V("wavelengths")'],
    "segments": ['V("segments")'],
    "scene": ['V("scene")'],
    "result": ['V("result")'],
    "focal_length": ["0.05"],
    "f_number": ["2.8"],
    "focus": ["2.0"],
    "d_o": ["2.0"],
    "pixel_pitch": ["5e-6"],
    "coc": ["3e-5"],
    "image_size": ["(8, 6)"],
    "shape": ["(6, 8)"],
    "width": ["8"],
    "height": ["6"],
    "n": ["5"],
    "factor": ["2"],
    "deficiency": ['"protan"'],
    "name": ['"D65"', '"srgb"', '"fuzz"'],
    "space": ['"srgb"'],
    "src": ['"srgb"'],
    "dst": ['"lab"', '"srgb"'],
    "method": ['"gray_world"'],
    "transfer": ['"srgb"'],
    "illuminant": ['"D65"'],
    "white": ['"D65"'],
    "src_white": ['"D65"'],
    "dst_white": ['"A"'],
    "path": ['V("tmpfile_png")'],
    "out_dir": ['V("tmpdir")'],
    "pattern": ['"RGGB"'],
    "cfa": ['"RGGB"'],
    "mask": ["np.ones((6, 8), dtype=bool)"],
    "falloff": ["np.full((6, 8), 0.8)"],
    "radius": ["2"],
    "sigma": ["1.0"],
    "rows": ["6"],
    "line_time": ["1e-5"],
    "exposure_time": ["0.01"],
    "exposure_time_s": ["0.01"],
    "irradiance": ["1.0"],
    "photons": ["np.full((6, 8), 1000.0)"],
    "signal": ["np.full((6, 8), 100.0)"],
    "wavelength_nm": ["550.0"],
    "system_gain": ["0.5"],
    "quantum_efficiency": ["0.6"],
    "up": ["(0.0, -1.0, 0.0)"],
    "eye": ["(0.0, 0.0, -5.0)"],
    "normal": ["(0.0, 0.0, -1.0)"],
    "center_m": ["(0.0, 0.0, 0.0)"],
    "magnification": ["0.1"],
    "gains": ["np.array([1.0, 1.1, 0.9])"],
    "matrix": ["np.eye(3)"],
    "degree": ["1"],
    "text": ['"hello"'],
    "title": ['"title"'],
    "value": ["1.0"],
    "kind": ['"linear"'],
    "stages": ["()"],
    "angle": ["0.3"],
    "axis": ['"x"'],
    "colors": ['"#ff0000,#00ff00,#0000ff"'],
    "a": ["np.array([1.0, 2.0])"],
    "b": ["np.array([2.0, 3.0])"],
    "v1": ["np.array([1.0, 2.0, 1.0])"],
    "v2": ["np.array([2.0, 3.0, 1.0])"],
    "fx": ["500.0"],
    "fy": ["500.0"],
    "cx": ["4.0"],
    "cy": ["3.0"],
    "focal_length_mm": ["4.0"],
    "pixel_pitch_um": ["3.0"],
    "dist_coeffs": ["np.zeros(5)"],
    "xy_": ['V("xy")'],
    "start": ["10.0"],
    "stop": ["200.0"],
    "convention": ['"cv2_lab_8u"', '"lab_8u"', '"hsv_8u"', '"hsv_full_8u"'],
    "chroma": ["np.full((3, 4, 2), 0.1)"],
    "primaries": ['V("spectrum3")'],
    "p": ["np.array([1.0, 2.0])"],
    "c": ["np.array([3.0, 4.0])"],
    "d": ["np.array([4.0, 5.0])"],
    "l1": ["np.array([1.0, 0.0, -2.0])"],
    "l2": ["np.array([0.0, 1.0, -3.0])"],
    "angles": ["np.array([0.1, 0.2, 0.3])"],
    "order": ['"xyz"'],
    "pitch": ["0.1"],
    "directions": ["np.eye(3)"],
    "principal_point": ["(4.0, 3.0)"],
    "v3": ["np.array([4.0, -800.0])"],
    "size": ["1.0"],
    "pattern_size": ["(4, 3)"],
    "fov_x": ["1.0"],
    "sensor_size_mm": ["(6.4, 4.8)"],
    "radius_px": ["np.full((6, 8), 1.0)", "1.0"],
    "abbe_number": ["60.0"],
    "aperture_diameter": ["0.01"],
    "sa_coefficient": ["0.1"],
    "pupil_radius": ["1.0"],
    "stop_radius": ["1.0"],
    "barrel_radius": ["1.2"],
    "barrel_distance": ["0.5"],
    "pixel_area": ["1e-11"],
    "dark_noise_e": ["2.0"],
    "mean_electrons": ["np.array([10.0, 100.0])"],
    "velocity": ["10.0"],
    "velocity_uv": ["(10.0, 0.0)"],
    "points_uv": ['V("uv")'],
    "mode": ['"rolling"'],
    "exposure_times": ["np.array([0.001, 0.002, 0.004])"],
    "rng": ["0"],
    "prnu": ["0.01"],
    "dsnu": ["1.0"],
    "column_fpn": ["0.5"],
    "key": ['"cie_1931_2"'],
    "functions": ['V("spectrum")'],
    "q": ["np.array([1.0, 0.0, 0.0, 0.0])"],
    "direction": ["np.array([0.0, 0.0, 1.0])"],
    "points_3d": ['V("points3")'],
    "points_2d": ['V("uv")'],
    "distortion": ['V("brown")'],
    "map_uv": ["np.zeros((6, 8, 2))"],
    "corners": ['V("uv")'],
    "images": ['[V("rgb_big")]'],
    "src_points": ['V("uv")'],
    "dst_points": ['V("uv")'],
    "choices": ['("a", "b")'],
    "what": ['"thing"'],
    "help": ['"help"'],
    "summary": ['"summary"'],
    "board": ['"9x6"'],
    "focal": ['"50mm"'],
}


def _alarm(signum: int, frame: Any) -> None:
    raise TimeoutError("bootstrap guess took more than 5 s")


def _try(func: Any, args_src: dict[str, str]) -> tuple[bool, str]:
    import numpy as np

    from tests.fuzz.values import V

    env = {"np": np, "V": V}
    kwargs = {k: resolve(eval(v, env)) for k, v in args_src.items()}
    signal.signal(signal.SIGALRM, _alarm)
    signal.alarm(5)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            func(**kwargs)
        return True, ""
    except BaseException as exc:
        return False, f"{type(exc).__name__}: {exc}".splitlines()[0][:120]
    finally:
        signal.alarm(0)


def guess(name: str, func: Any, prefix: str = "call(") -> str:
    try:
        sig = inspect.signature(func)
    except (TypeError, ValueError):
        return 'Skip("no signature")'
    req = [
        p
        for p in sig.parameters.values()
        if p.default is p.empty
        and p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD)
        and p.name != "self"
    ]
    if any(p.kind is p.POSITIONAL_ONLY for p in req):
        return 'Skip("positional-only parameters")'
    options = [GUESS.get(p.name, [None]) for p in req]
    if any(o == [None] for o in options):
        missing = [p.name for p, o in zip(req, options, strict=True) if o == [None]]
        return f'Skip("TODO: no guess for {", ".join(missing)}")'
    err = ""
    for combo in itertools.islice(itertools.product(*options), 12):
        src = {p.name: s for p, s in zip(req, combo, strict=True)}
        ok, e = _try(func, src)
        if ok:
            return prefix + ", ".join(f"{k}={v}" for k, v in src.items()) + ")"
        err = err or e
    return f"Skip({('TODO: ' + err)!r})"


def main(argv: list[str]) -> None:
    from tests.fuzz.table import VALID

    redo = "--all" in argv
    only = [a for a in argv if not a.startswith("--")]
    for name, func in public_callables().items():
        if only and not any(name.startswith(o) for o in only):
            continue
        entry0 = VALID.get(name)
        todo = isinstance(entry0, Skip) and entry0.reason.startswith(("TODO", "no valid instance"))
        if name in VALID and not (redo or todo):
            continue
        if (
            "." in name
            and name.rsplit(".", 1)[0] in public_callables()
            and inspect.isclass(public_callables()[name.rsplit(".", 1)[0]])
        ):
            owner = name.rsplit(".", 1)[0]
            entry = VALID.get(owner)
            raw = inspect.getattr_static(public_callables()[owner], name.rsplit(".", 1)[1])
            if isinstance(raw, staticmethod | classmethod):
                print(f"    {name!r}: {guess(name, func)},")
            elif isinstance(entry, C):
                try:
                    from tests.fuzz.values import resolve as _r

                    inst = func_owner = public_callables()[owner]
                    inst = func_owner(*_r(entry.args), **_r(entry.kwargs))
                    bound = getattr(inst, name.rsplit(".", 1)[1])
                    text = guess(name, bound, prefix=f"method(VALID[{owner!r}], ")
                    text = text.replace(", )", ")")
                except Exception as exc:
                    text = f"Skip({('TODO: instance: ' + str(exc).splitlines()[0][:100])!r})"
                print(f"    {name!r}: {text},")
            else:
                print(f"    {name!r}: Skip('no valid instance of {owner.rsplit('.', 1)[1]}'),")
            continue
        print(f"    {name!r}: {guess(name, func)},")
        sys.stdout.flush()


if __name__ == "__main__":
    main(sys.argv[1:])
