"""Building blocks of the self-contained simulation report.

The page skeleton with inline CSS, figures as base64 ``data:`` URIs, tables and notes. Every text is
HTML-escaped here.
"""

from __future__ import annotations

import base64
import html
import io
from collections.abc import Iterable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from imageform._jsonio import dumps
from imageform._typing import ArrayLike
from imageform._validate import as_int, describe, format_shape
from imageform.errors import InvalidInputError

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = [
    "CSS",
    "Markup",
    "e",
    "figure",
    "figure_png",
    "img_tag",
    "json_block",
    "note",
    "page",
    "page_jpeg",
    "section",
    "table",
]

CSS = """
:root { color-scheme: light; }
body { font: 15px/1.45 system-ui, -apple-system, "Segoe UI", Roboto, sans-serif; margin: 0;
       color: #1d1d1f; background: #fafafa; }
main { max-width: 1320px; margin: 0 auto; padding: 1.2em 1.6em 4em; }
h1 { font-size: 1.7em; margin: 0.2em 0 0.1em; }
h2 { border-bottom: 2px solid #ddd; padding-bottom: 0.2em; margin-top: 2.2em; }
nav a { margin-right: 1em; }
figure { margin: 1.2em 0; background: #fff; border: 1px solid #e3e3e3; border-radius: 6px;
         padding: 0.8em; }
figure img { display: block; max-width: 100%; height: auto; margin: 0 auto;
             image-rendering: auto; }
figure img.photo { width: 100%; }
figcaption { font-size: 0.92em; color: #333; margin-top: 0.5em; }
figcaption .meta { color: #666; font-size: 0.9em; }
table { border-collapse: collapse; margin: 0.8em 0; font-size: 0.9em; background: #fff; }
th, td { border: 1px solid #ddd; padding: 0.25em 0.6em; text-align: right; }
th { background: #f0f0f0; }
td.l, th.l { text-align: left; }
.swatch { display: inline-block; width: 1.1em; height: 1.1em; border: 1px solid #555;
          vertical-align: middle; }
.note { background: #fff7e0; border-left: 4px solid #e0a800; padding: 0.5em 0.8em; }
pre { background: #fff; border: 1px solid #e3e3e3; padding: 0.8em; overflow: auto;
      font-size: 0.85em; }
.grid { display: grid; grid-template-columns: repeat(auto-fill, minmax(560px, 1fr));
        gap: 0 1.2em; }
"""


def e(text: Any) -> str:
    """HTML-escaped ``str(text)``."""
    return html.escape(str(text), quote=True)


def _image_bytes(png: object, name: str = "png") -> bytes:
    """Return the encoded image's bytes (bytes, bytearray or memoryview).

    Anything else is a TypeError naming ``name``.
    """
    if not isinstance(png, bytes | bytearray | memoryview):
        raise TypeError(f"expected {name} as the bytes of an encoded image, got {describe(png)}")
    return bytes(png)


def _strings(value: object, name: str) -> list[Any]:
    """Return a list of the items of a sequence (not a str or bytes).

    Anything else is a TypeError naming ``name``.
    """
    if isinstance(value, str | bytes) or not isinstance(value, Iterable):
        raise TypeError(f"expected {name} as a sequence, got {describe(value)}")
    return list(value)


def img_tag(png: bytes, alt: str, *, photo: bool = False, mime: str = "image/png") -> str:
    """Return an ``<img>`` whose source is the encoded image itself, base64 in a ``data:`` URI.

    ``png`` holds the bytes of a PNG, or of a JPEG with ``mime="image/jpeg"``; a ``photo`` (a stage
    image) is shown as wide as the page.
    """
    b64 = base64.b64encode(_image_bytes(png)).decode("ascii")
    cls = ' class="photo"' if photo else ""
    return f'<img{cls} src="data:{mime};base64,{b64}" alt="{e(alt)}">'


#: The widest picture the page embeds (px): the page's column is at most 1320 px wide.
PAGE_IMAGE_MAX_WIDTH = 1280
#: JPEG quality of the pictures embedded in the page (the lossless files are in stages/).
PAGE_JPEG_QUALITY = 85


def page_jpeg(
    rgb: ArrayLike, *, max_width: int = PAGE_IMAGE_MAX_WIDTH, quality: int = PAGE_JPEG_QUALITY
) -> bytes:
    """Encode an 8-bit RGB picture ``(H, W, 3)`` (or a PIL image) as JPEG bytes for the page.

    It is scaled down (area average) to at most ``max_width`` pixels wide. For display only: the
    lossless PNG of a stage is written to stages/ and linked from the page.
    """
    from PIL import Image

    max_width = as_int(max_width, "max_width", minimum=1)
    quality = as_int(quality, "quality", minimum=1, maximum=95)
    im = rgb if isinstance(rgb, Image.Image) else Image.fromarray(_rgb8(rgb), "RGB")
    im = im.convert("RGB")
    if im.width > max_width:
        h = max(1, round(im.height * max_width / im.width))
        im = im.resize((max_width, h), Image.Resampling.BOX)
    buf = io.BytesIO()
    im.save(buf, format="JPEG", quality=quality)
    return buf.getvalue()


def _rgb8(rgb: object) -> np.ndarray:
    """``rgb`` as a non-empty uint8 array of shape (H, W, 3), else an error naming it."""
    arr = np.asarray(rgb) if isinstance(rgb, np.ndarray) else None
    if arr is None or arr.dtype != np.uint8 or arr.ndim != 3 or arr.shape[-1] != 3:
        raise InvalidInputError(
            f"expected rgb as a uint8 array of shape (H, W, 3) or a PIL image, got {describe(rgb)}"
        )
    if arr.size == 0:
        raise InvalidInputError(f"expected rgb non-empty, got shape {format_shape(arr.shape)}")
    return np.ascontiguousarray(arr)


def figure_png(fig: Figure, dpi: int = 100) -> bytes:
    """Return the matplotlib figure as PNG bytes; the figure is closed."""
    import matplotlib.pyplot as plt

    buf = io.BytesIO()
    try:
        # zlib level 1: a little larger, several times faster to write than the default 6
        fig.savefig(buf, format="png", dpi=dpi, pil_kwargs={"compress_level": 1})
    finally:
        plt.close(fig)
    return buf.getvalue()


def figure(
    png: bytes,
    alt: str,
    caption_html: str,
    fig_id: str | None = None,
    *,
    photo: bool = False,
    mime: str = "image/png",
    href: str | None = None,
) -> str:
    """Return a ``<figure>`` with the embedded image and a caption.

    ``png``: the image's bytes (a JPEG's with ``mime="image/jpeg"``); ``caption_html`` is trusted:
    build it from escaped parts. With ``href`` (a relative link, e.g. the lossless stage file) the
    image links to it.
    """
    ident = f' id="{e(fig_id)}"' if fig_id else ""
    img = img_tag(png, alt, photo=photo, mime=mime)
    if href is not None:
        img = f'<a href="{e(href)}">{img}</a>'
    return f"<figure{ident}>{img}<figcaption>{caption_html}</figcaption></figure>"


def note(text: str) -> str:
    """Return a highlighted note (escaped)."""
    return f'<p class="note">{e(text)}</p>'


def section(ident: str, title: str, body: str) -> str:
    """Return a ``<section>`` with an anchor and a heading."""
    return f'<section id="{e(ident)}"><h2>{e(title)}</h2>{body}</section>'


def table(header: Sequence[str], rows: Sequence[Sequence[Any]], left: Sequence[int] = ()) -> str:
    """Return an HTML table; cells are escaped unless they are ``Markup``.

    ``Markup`` is a str subclass marking trusted HTML; columns listed in ``left`` are left-aligned.
    """

    def cell(tag: str, j: int, v: Any) -> str:
        cls = ' class="l"' if j in left else ""
        return f"<{tag}{cls}>{v if isinstance(v, Markup) else e(v)}</{tag}>"

    if isinstance(left, str | bytes) or not (
        isinstance(left, Sequence | set | frozenset)
        and all(isinstance(j, int) and not isinstance(j, bool) for j in left)
    ):
        raise TypeError(f"expected left as column numbers (int), got {describe(left)}")
    heads = _strings(header, "header")
    body_rows = [_strings(r, f"rows[{i}]") for i, r in enumerate(_strings(rows, "rows"))]
    head = "".join(cell("th", j, h) for j, h in enumerate(heads))
    body = "".join(
        "<tr>" + "".join(cell("td", j, v) for j, v in enumerate(r)) + "</tr>" for r in body_rows
    )
    return f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


class Markup(str):
    """Trusted HTML (already escaped) for :func:`table` cells."""

    __slots__ = ()


def json_block(value: Any, summary: str) -> str:
    """Collapsible pretty-printed JSON."""
    try:
        text = dumps(value)
    except (TypeError, ValueError) as exc:
        raise TypeError(f"expected value as JSON-serialisable data: {exc}"[:200]) from None
    return f"<details><summary>{e(summary)}</summary><pre>{e(text)}</pre></details>"


def page(title: str, subtitle_html: str, nav: Sequence[tuple[str, str]], body: str) -> str:
    """Return the whole document: no external resource, no script needed to view it."""
    pairs = _strings(nav, "nav")
    if not all(isinstance(p, tuple | list) and len(p) == 2 for p in pairs):
        raise TypeError(f"expected nav as (anchor, title) pairs, got {describe(nav)}")
    links = " ".join(f'<a href="#{e(i)}">{e(t)}</a>' for i, t in pairs)
    return (
        "<!DOCTYPE html>\n"
        '<html lang="en"><head><meta charset="utf-8">'
        '<meta name="viewport" content="width=device-width, initial-scale=1">'
        '<link rel="icon" href="data:,">'
        f"<title>{e(title)}</title><style>{CSS}</style></head>"
        f"<body><main><header><h1>{e(title)}</h1>{subtitle_html}"
        f"<nav>{links}</nav></header>{body}</main></body></html>\n"
    )
