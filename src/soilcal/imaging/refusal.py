"""What was tried on a photo that could not be measured: one diagnostic image per refusal.

A refusal names what was not found (``InputError``: file, field, expected, got).  With a
refusals folder (the workflow's ``logs/<soil>/images/refused/``, the command line's
``--refusals``, default the current folder) the photo's attempts are also drawn into
``<folder>/<photo stem>.refused.png`` (never a name a photo beside it could have) and
the message ends with that file's path, so a user sees where the plate line was looked for,
which segmentation was tried on it and why each attempt was turned down:

* panel (a): the photo with every plate-line candidate (numbered from the top);
* the grey level and the edge map the candidates came from;
* one panel per attempt (at most :data:`MAX_ATTEMPTS`): the segmented class in red over the
  photo, the plate line it was tried on, the cue and polarity, and the reason it was turned
  down.

A measurement records its attempts in a :class:`Tried` (pile photos: every plate line and
cue; drum frames: the drum circle found and the surface mask; furrow photos: the binary
image), and :func:`explained` turns a refusal into the image and the longer message.  The
image is written only for a refusal; a measured photo writes nothing here.
"""

from __future__ import annotations

from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from soilcal.errors import InputError

MAX_ATTEMPTS = 6  # attempts drawn on one diagnostic image


@dataclass
class Attempt:
    label: str  # e.g. "line 1, chroma/dark"
    mask: np.ndarray | None = None  # the class segmented (bool, image shape)
    line: tuple | None = None  # (slope, intercept) of the plate line tried, row = slope * col + b
    circle: tuple | None = None  # (col, row, radius) of a drum
    outcome: str = ""  # why it was turned down


@dataclass
class Tried:
    """The attempts on one photo (filled in by the measurement as it goes)."""

    rgb: np.ndarray | None = None
    gray: np.ndarray | None = None
    edges: np.ndarray | None = None
    lines: list = field(default_factory=list)  # plate-line candidates (slope, intercept)
    attempts: list = field(default_factory=list)
    keep_masks: bool = True  # False: attempts without their masks (no image will be drawn)

    def add(self, label, mask=None, line=None, circle=None) -> Attempt:
        keep = mask is not None and self.keep_masks
        a = Attempt(label, np.array(mask, bool) if keep else None, line, circle)
        self.attempts.append(a)
        return a

    def refuse_last(self, exc: Exception) -> None:
        """The last attempt was turned down by ``exc``."""
        if self.attempts and not self.attempts[-1].outcome:
            self.attempts[-1].outcome = _reason(exc)


def _reason(exc: Exception) -> str:
    if isinstance(exc, InputError):
        got = "" if exc.got is None else f", got {exc.got}"
        return f"{exc.field}: expected {exc.expected}{got}"
    return str(exc)


def _wrap(text: str, width: int = 46, lines: int = 4) -> str:
    import textwrap

    out = textwrap.wrap(text, width)
    if len(out) > lines:
        out = out[:lines]
        out[-1] = out[-1][: width - 3] + "..."
    return "\n".join(out)


def _draw_line(ax, line, w, **kw):
    slope, b = line
    cols = np.array([0.0, w - 1.0])
    ax.plot(cols, slope * cols + b, **kw)


def refusal_path(photo, folder) -> Path:
    """Where the diagnostic image of the refused ``photo`` goes: ``folder/<stem>.refused.png``."""
    return Path(folder) / f"{Path(photo).stem}.refused.png"


def write_diagnostic(photo, exc: Exception, tried: Tried, folder) -> Path:
    """Draw ``tried`` for the refused ``photo`` into ``folder/<stem>.refused.png``; returns the path."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    photo = Path(photo)
    rgb = tried.rgb
    out = refusal_path(photo, folder)
    out.parent.mkdir(parents=True, exist_ok=True)
    attempts = tried.attempts[:MAX_ATTEMPTS]
    panels = 1 + (tried.gray is not None or rgb is not None) + (tried.edges is not None) + len(attempts)
    ncol = min(4, panels)
    nrow = int(np.ceil(panels / ncol))
    fig, axes = plt.subplots(nrow, ncol, figsize=(4.2 * ncol, 3.6 * nrow + 0.8), squeeze=False)
    axes = list(axes.ravel())
    k = 0
    ax = axes[k]
    if rgb is not None:
        h, w = rgb.shape[:2]
        ax.imshow(rgb)
        for n, ln in enumerate(tried.lines, 1):
            _draw_line(ax, ln, w, lw=1.0, label=f"plate line {n}")
            ax.text(2, ln[1] + ln[0] * 2, str(n), color="yellow", fontsize=8, va="bottom")
        if tried.lines:
            ax.legend(fontsize=6, loc="upper right")
        ax.set_xlim(0, w - 1)
        ax.set_ylim(h - 1, 0)
    ax.set_title(f"(a) photo, {len(tried.lines)} plate-line candidates", fontsize=8)
    k += 1
    if tried.gray is not None or rgb is not None:
        from skimage import color

        gray = tried.gray if tried.gray is not None else color.rgb2gray(rgb[..., :3]) if rgb.ndim == 3 else rgb
        axes[k].imshow(gray, cmap="gray")
        axes[k].set_title("(b) grey level", fontsize=8)
        k += 1
    if tried.edges is not None:
        axes[k].imshow(tried.edges, cmap="gray")
        axes[k].set_title("(c) edges the plate lines were sought in", fontsize=8)
        k += 1
    for n, a in enumerate(attempts):
        ax = axes[k]
        k += 1
        if rgb is not None:
            ax.imshow(rgb, alpha=0.55)
            h, w = rgb.shape[:2]
        elif a.mask is not None:
            h, w = a.mask.shape
        else:
            h = w = None
        if a.mask is not None:
            over = np.zeros(a.mask.shape + (4,))
            over[a.mask] = (1.0, 0.0, 0.0, 0.45)
            ax.imshow(over)
        if a.line is not None and w is not None:
            _draw_line(ax, a.line, w, color="c", lw=1.2)
        if a.circle is not None:
            cx, cy, r = a.circle
            t = np.linspace(0, 2 * np.pi, 361)
            ax.plot(cx + r * np.cos(t), cy + r * np.sin(t), "c-", lw=1.0)
        if w is not None:
            ax.set_xlim(0, w - 1)
            ax.set_ylim(h - 1, 0)
        ax.set_title(f"attempt {n + 1}: {a.label}\n" + _wrap(a.outcome or "not tried to the end"), fontsize=7)
    for ax in axes:
        ax.set_axis_off()
    more = len(tried.attempts) - len(attempts)
    fig.suptitle(_wrap(f"{photo.name} refused: {_reason(exc)}" + (f" ({more} more attempts not drawn)" if more > 0 else ""),
                       width=120, lines=3), fontsize=9)
    fig.tight_layout()
    fig.savefig(out, dpi=90)
    plt.close(fig)
    return out


@contextmanager
def explained(photo, folder, tried: Tried):
    """Run a measurement; on a refusal (``InputError``) about ``photo`` with a ``folder``,
    write the diagnostic image and re-raise the refusal naming it.  A photo that could not
    be read at all (an unreadable or blank file) has nothing to draw: its refusal is
    re-raised as it is."""
    try:
        yield tried
    except InputError as exc:
        if folder is None or exc.path != str(photo) or tried.rgb is None:
            raise
        tried.refuse_last(exc)
        png = write_diagnostic(photo, exc, tried, folder)
        raise InputError(exc.path, exc.field, exc.expected, exc.got, note=f"what was tried: {png}") from None


__all__ = ["Attempt", "MAX_ATTEMPTS", "Tried", "explained", "refusal_path", "write_diagnostic"]
