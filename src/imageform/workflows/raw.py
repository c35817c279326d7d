"""Raw workflows: ``imageform develop`` (a raw file through imageform's own pipeline)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal, get_args

from imageform._files import RAW_SUFFIXES
from imageform.workflows._images import Device, ImageOut, image_out_renames, write
from imageform.workflows._spec import Input, Options, Output, Result, Run, Workflow, option

__all__ = ["WORKFLOWS", "DevelopOptions"]


#: ``develop --white-balance``: the as-shot gains, LibRaw's automatic or daylight gains, or none.
_RawWhiteBalance = Literal["camera", "auto", "daylight", "none"]
#: ``develop --transfer``: the encodings of imageform.color.TRANSFER_FUNCTIONS but "gamma".
_RawTransfer = Literal["srgb", "rec709", "rec2020", "adobe_rgb", "prophoto", "linear"]


@image_out_renames
@dataclass(frozen=True, kw_only=True)
class DevelopOptions(ImageOut, Options):
    """Options of ``imageform develop``."""

    demosaic: str = option(
        "bilinear",
        help="Demosaicing method (bilinear matches LibRaw's LINEAR).",
        choices="imageform.sensor.demosaic:DEMOSAIC_METHODS",
    )
    white_balance: _RawWhiteBalance = option(
        "camera",
        help="White balance: the as-shot gains (camera; a file with none: auto, with a note), "
        "LibRaw's automatic (auto, the image's average) or daylight gains, or none.",
        choices=get_args(_RawWhiteBalance),
    )
    space: str = option(
        "srgb",
        help="Output RGB space (see imageform.color.RGB_SPACES).",
        choices="imageform.color:RGB_SPACES",
    )
    linear: bool = option(False, help="Leave the output linear (no transfer function).")
    transfer: _RawTransfer | None = option(
        None,
        help="Encode with this curve instead of the space's own (rec709: LibRaw's default).",
        choices=get_args(_RawTransfer),
    )
    auto_bright: bool = option(
        False,
        help="Brighten as LibRaw does by default: 1 % of the brightest channel's pixels at white.",
    )
    baseline_exposure: bool = option(
        False,
        help="Brighten by the DNG's BaselineExposure (2^EV), as Adobe's readers do; LibRaw "
        "ignores it. Not with --auto-bright.",
    )
    highlight_rolloff: bool = option(
        False,
        help="With --baseline-exposure or --auto-bright: roll the brightened highlights off "
        "smoothly into white (kept up to 0.8 linear, white at the sensor's white) instead of "
        "clipping them.",
    )
    opcodes: bool = option(
        True,
        help="Apply a DNG's opcodes as Adobe's DNG SDK does: GainMaps (the lens-shading "
        "correction phones write) and the other per-pixel ones to the mosaic, then after "
        "demosaicing WarpRectilinear (lens distortion), FixVignetteRadial and GainMap; "
        "--no-opcodes leaves them, as LibRaw does.",
    )
    device: Device = option(
        "cpu",
        help="Where the development runs: cuda develops bilinear and Malvar Bayer mosaics in "
        "one GPU kernel (numba's CUDA target; refused in one line when no GPU is usable).",
        choices=get_args(Device),
    )

    def check(self) -> None:
        """Refuse ``--auto-bright`` with ``--baseline-exposure`` (both set the brightness)."""
        super().check()
        if self.auto_bright and self.baseline_exposure:
            from imageform.errors import InvalidInputError

            raise InvalidInputError(
                "--auto-bright and --baseline-exposure both set the brightness: give one of them"
            )


def raw_layout(img: Any) -> str:
    """Describe a :class:`~imageform.io.RawImage`'s sensor layout in words."""
    if img.cfa_pattern:
        return f"{img.cfa_pattern} mosaic"
    if img.metadata.get("xtrans"):
        return "X-Trans mosaic (demosaiced by LibRaw's linear interpolation)"
    return "monochrome raw" if img.monochrome else "linear (demosaiced) raw"


def stage3_names(meta: dict[str, Any]) -> list[str]:
    """Name the OpcodeList3 opcodes a read kept for development (``"OpcodeList3:..."``)."""
    return [f"OpcodeList3:{type(op).__name__}" for op in meta.get("opcodes_stage3") or ()]


def opcode_notes(meta: dict[str, Any], *, developed: bool = False) -> list[str]:
    """Say which DNG opcodes a read applied (GainMaps), which develop applies, which neither.

    ``developed``: the development says itself that it applied the OpcodeList3 opcodes.
    """
    notes = []
    if meta.get("opcodes_applied"):
        n = int(meta["opcodes_applied"])
        notes.append(f"applied the DNG's {n} GainMap opcode{'s' if n > 1 else ''} (lens shading)")
    decoded = meta.get("opcodes_decoded") or []
    if decoded:
        notes.append(
            f"the lossy DNG's samples decoded with its {', '.join(dict.fromkeys(decoded))} "
            "(as LibRaw decodes them; not applied again)"
        )
    other = meta.get("opcodes_applied_other") or []
    if other:
        notes.append(f"applied the DNG's {', '.join(dict.fromkeys(other))}")
    later = stage3_names(meta)
    if later and not developed:
        names = ", ".join(dict.fromkeys(later))
        notes.append(f"DNG opcodes applied when developed (after demosaicing): {names}")
    skipped = meta.get("opcodes_skipped") or []
    if skipped:
        names = ", ".join(dict.fromkeys(skipped))
        notes.append(f"DNG opcodes not applied: {names}")
    return notes


def raw_info(path: Path) -> Result:
    """``imageform info`` of a raw file: its sensor layout and levels (``read_raw``)."""
    import numpy as np

    from imageform.io import read_raw

    raw = read_raw(path)
    h, w = raw.mosaic.shape[:2]
    kind = raw_layout(raw)
    summary = {
        "image": path,
        "format": "raw",
        "width": w,
        "height": h,
        "layout": kind,
        "cfa_pattern": raw.cfa_pattern,
        "black_level": np.asarray(raw.black_level).tolist(),
        "white_level": raw.white_level,
        "camera_model": raw.metadata.get("camera_model"),
        "calibration_illuminant": raw.calibration_illuminant,
        "as_shot_white_balance": None
        if raw.white_balance is None
        else np.asarray(raw.white_balance).tolist(),
        "orientation": raw.orientation,
        "opcodes_applied": int(raw.metadata.get("opcodes_applied", 0)),
        "opcodes_skipped": list(raw.metadata.get("opcodes_skipped", [])),
        "opcodes_applied_other": list(raw.metadata.get("opcodes_applied_other", [])),
        "opcodes_decoded": list(raw.metadata.get("opcodes_decoded", [])),
        "opcodes_at_development": stage3_names(raw.metadata),
        "baseline_exposure_ev": raw.metadata.get("baseline_exposure_ev"),
    }
    model = summary["camera_model"] or "camera not named"
    text = [
        f"{path}: raw ({model}), {w} x {h} photosites, {kind}",
        f"black level {np.round(np.asarray(raw.black_level), 1).tolist()}, white level "
        f"{raw.white_level:g}; develop with imageform develop",
        *opcode_notes(raw.metadata),
    ]
    ev = summary["baseline_exposure_ev"]
    if ev:  # the camera's recommended exposure offset: applied only when asked
        text.append(
            f"BaselineExposure {ev:+.2f} EV (develop --baseline-exposure applies it"
            + (", --highlight-rolloff keeps the highlights it would clip)" if ev > 0 else ")")
        )
    return Result(summary, tuple(text))


def develop(run: Run, opts: DevelopOptions, *, raw: Path, out: Path) -> Result:
    """Read the raw file, develop it step by step, write the image."""
    import numpy as np

    if opts.device == "cuda":  # refused in one line before any file is read
        from imageform._cuda.geometry import require_cuda

        require_cuda("--device cuda")

    from imageform.io import develop as develop_raw
    from imageform.io import image_format, read_raw

    img = read_raw(raw, opcodes=opts.opcodes)
    for note in opcode_notes(img.metadata, developed=True):
        run.note(note)
    dev = develop_raw(
        img,
        demosaic=opts.demosaic,
        white_balance=opts.white_balance,
        space=opts.space,
        linear=opts.linear,
        device=opts.device,
        transfer=opts.transfer,
        auto_bright=opts.auto_bright,
        baseline_exposure=opts.baseline_exposure,
        highlight_rolloff=opts.highlight_rolloff,
    )
    for note in dev.notes:
        run.note(note)
    # a developed raw is 16 bits a channel in PNG (docs/raw.md) unless --bit-depth says otherwise;
    # 16-bit samples come straight from the developer (a bilinear Bayer development writes them
    # in its one fused pass, no float image made), the same values as rounding the float image
    fmt = image_format(out)
    if (fmt == "png" and opts.bit_depth in (None, 16)) or (fmt == "tiff" and opts.bit_depth == 16):
        image = dev.to_integer(16)
    else:
        image = dev.image
    from imageform.io.icc import encoded_space

    tag = encoded_space(dev.space, dev.transfer)  # viewers then show the colours as meant
    write(run, out, image, opts, like=np.zeros(1, np.uint16), color_space=tag)
    h, w = img.mosaic.shape[:2]
    oh, ow = image.shape[:2]
    kind = raw_layout(img)
    summary: dict[str, Any] = {
        "raw": raw,
        "out": out,
        "size": [w, h],
        "output_size": [ow, oh],
        "cfa_pattern": img.cfa_pattern,
        "monochrome": img.monochrome,
        "xtrans": img.metadata.get("xtrans"),
        "black_level": np.asarray(img.black_level).tolist(),
        "white_level": img.white_level,
        "gains": dev.gains.tolist(),
        "camera_to_xyz": dev.camera_to_xyz.tolist(),
        "calibration_illuminant": img.calibration_illuminant,
        "demosaic": dev.demosaic,
        "device": opts.device,
        "space": dev.space,
        "transfer": dev.transfer,
        "icc_profile": tag if tag not in (None, "srgb") else None,
        "brightness": dev.brightness,
        "orientation": {"flip": img.orientation, "applied": dev.orientation == img.orientation},
        "notes": list(dev.notes),
    }
    gains = ", ".join(f"{g:.3f}" for g in dev.gains)
    turned = (
        f", turned for display (flip {img.orientation}) to {ow}x{oh}" if img.orientation else ""
    )
    text = (
        f"{raw.name}: {w}x{h} {kind}, black {np.mean(img.black_level):g}, "
        f"white {img.white_level:g}{turned}",
        f"white balance {opts.white_balance} (gains {gains}), {dev.demosaic} demosaicing, "
        f"{dev.space} ({dev.transfer}) -> {out}",
    )
    return Result(summary, text)


WORKFLOWS = (
    Workflow(
        "develop",
        "Develop a raw file (DNG, CR2, NEF, ARW, ...) with imageform's own pipeline.",
        "imageform.workflows.raw:develop",
        DevelopOptions,
        (
            Input(
                "raw",
                "Raw file LibRaw reads (needs imageform[raw]; the DNG imageform writes does not).",
                metavar="RAW",
                suffixes=RAW_SUFFIXES,
            ),
        ),
        Output("Output image (PNG 16-bit by default, JPEG, TIFF float32, .npy)."),
        batch=True,
        group="colour",
        description="Linearise (black and white levels), white balance, demosaic, camera RGB "
        "to XYZ from the file's colour matrix, adaptation to the output white, encoding.",
    ),
)
