"""Figures of the image pipeline as the papers show them (002 Fig. 4, 003 Fig. 2):
(a) original, (b) gray, (c) binary, (d) contour, (e) fitted lines; furrow: photo, binary and
the profile with its polynomial F(x).  Every figure is written as <stem>.png (dpi 150) and
<stem>.pdf.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def check_apart(photos, folder, field):
    """Refuse (InputError naming the first photo at fault and ``field``) a ``folder`` for figures
    that is the folder of one of ``photos``, before anything is measured or written: figures are
    written as <photo's name>.png / .pdf, which there would replace a PNG photo of that name
    (the one measured, or another photo beside it: x.jpg's figure x.png over a photo x.png).
    The folders are compared as the files they are (:func:`os.path.samefile`), so a symlinked,
    relative or differently spelled path to the same folder is the same folder.  A folder that
    does not exist yet is no photo's."""
    import os

    from soilcal.errors import InputError

    if folder is None or not Path(folder).is_dir():
        return
    for photo in photos:
        parent = Path(photo).parent
        if parent.is_dir() and os.path.samefile(parent, folder):
            stem = Path(photo).stem
            raise InputError(photo, field, f"a folder for the figures other than the photo's own (its figure "
                             f"is written as {stem}.png and {stem}.pdf, which there would replace a photo of "
                             f"that name)", str(folder))


def _named(stem, suffix):
    """``stem`` with ``suffix`` added: a photo's name may hold dots of its own (heap.v2.png has
    the stem heap.v2), which Path.with_suffix would take for an extension and replace."""
    stem = Path(stem)
    return stem.with_name(stem.name + suffix)


def _not_over_photo(result, stem):
    """Refuse (InputError naming the photo) to write the figures ``stem``.png / .pdf of
    ``result`` where one of them is the photo measured itself: a figures folder that is the
    photos' own folder, a PNG photo, would have the photo replaced by its figure."""
    from soilcal.errors import InputError

    photo = Path(result.path)
    for out in (_named(stem, ".png"), _named(stem, ".pdf")):
        if photo.is_file() and out.exists() and out.resolve() == photo.resolve():
            raise InputError(photo, "figures folder", f"a folder other than the photo's own for its figures "
                             f"(its figure {out.name} would replace the photo)",
                             str(Path(stem).parent))


def _save(fig, stem):
    stem = Path(stem)
    stem.parent.mkdir(parents=True, exist_ok=True)
    png, pdf = _named(stem, ".png"), _named(stem, ".pdf")
    fig.savefig(png, dpi=150)
    fig.savefig(pdf)
    plt.close(fig)
    return png, pdf


def low_flag(result) -> str:
    """What the title of ``result``'s figure says of its confidence: "" for an "ok" heap photo
    or drum frame, else "confidence low: <reason>", or "confidence low, accepted by the user
    (accept_low): <reason>" for a drum frame the user accepted, so that its figure, checked by
    eye, shows the flag."""
    if getattr(result, "confidence", "ok") == "ok":
        return ""
    why = getattr(result, "low_reason", None)
    if why is None:  # a heap photo: its reason is worked out from its result
        from soilcal.imaging.measure import low_reason

        why = low_reason(result)
    head = ("confidence low, accepted by the user (accept_low)" if getattr(result, "accepted_by_user", False)
            else "confidence low")
    return f"{head}: {why}"


def angle_figure(result, stem, title=""):
    """Five panels for a pile photo or a drum frame measured with ``keep_stages=True``; the
    title says a result flagged low and why (:func:`low_flag`)."""
    import textwrap

    _not_over_photo(result, stem)
    st = result.stages
    flag = textwrap.wrap(low_flag(result), 190)
    fig, ax = plt.subplots(1, 5, figsize=(17, 3.4 + 0.17 * len(flag)))
    ax[0].imshow(st.rgb)
    ax[0].set_title("(a) original")
    ax[1].imshow(st.gray, cmap="gray")
    ax[1].set_title("(b) gray (segmentation channel)")
    ax[2].imshow(st.binary, cmap="gray")
    ax[2].set_title("(c) binary")
    ax[3].imshow(st.level, cmap="gray")
    ax[3].contour(st.level, [0.5], colors="r", linewidths=0.8)
    if st.plate_row is not None:
        ax[3].axhline(st.plate_row, color="c", lw=0.8)
    if st.circle is not None:
        cx, cy, r = st.circle
        a = np.linspace(0, 2 * np.pi, 361)
        ax[3].plot(cx + r * np.cos(a), cy + r * np.sin(a), "c-", lw=0.8)
    ax[3].set_title("(d) contour, " + st.reference, fontsize=8)
    for pts in st.points:
        ax[4].plot(pts[:, 0], pts[:, 1], ".", ms=1.5)
    allp = np.vstack(st.points)
    for u0, v0, du, dv, lab in st.lines:
        proj = (allp[:, 0] - u0) * du + (allp[:, 1] - v0) * dv
        t = np.array([proj.min(), proj.max()]) * 1.3
        ang = np.degrees(np.arctan2(abs(dv), abs(du)))
        ax[4].plot(u0 + t * du, v0 + t * dv, "-", lw=1, label=f"{lab}: {ang:.2f} deg")
    ax[4].set_aspect("equal")
    ax[4].set_xlabel("u / px (along the level)")
    ax[4].set_ylabel("v / px (up)")
    ax[4].legend(fontsize=7)
    ax[4].set_title(f"(e) fitted lines, {result.angle_deg:.2f} deg")
    for a in ax[:4]:
        a.set_axis_off()
    fig.suptitle("\n".join([title or Path(result.path).name, *flag]), color="firebrick" if flag else "black",
                 fontsize=10 if flag else None)
    fig.tight_layout()
    return _save(fig, stem)


def angle_figures(results, folder):
    """Each heap photo's or drum frame's angle figure in ``folder``, named by the photo's file
    name without its extension (:func:`angle_figure` adds ``.png`` and ``.pdf``)."""
    for r in results:
        angle_figure(r, Path(folder) / Path(r.path).stem)


def furrow_figure(result, stem, title=""):
    _not_over_photo(result, stem)
    st = result.stages
    fig, ax = plt.subplots(1, 3, figsize=(15, 3.8))
    ax[0].imshow(st.rgb)
    ax[0].set_title("(a) original")
    ax[1].imshow(st.binary, cmap="gray")
    ax[1].set_title("(b) soil found below the beam")
    ax[2].plot(result.x_mm, result.z_mm, ".", ms=1, label="contour")
    x = np.linspace(result.x_mm.min(), result.x_mm.max(), 400)
    ax[2].plot(x, np.polyval(result.coeffs, x), "r-", lw=1, label=f"degree-{result.degree} fit")
    if len(result.chord_ends_mm) == 2 and st.frame is not None:
        half = 0.5 * (st.frame[1] - st.frame[0]) / st.frame[3]  # the beam's span, mm
        ax[2].plot([-half, half], result.chord_ends_mm, "k--", lw=1,
                   label="chord (ends: " + ", ".join(result.chord_ends_from) + ")")
    ax[2].set_xlabel("x / mm")
    ax[2].set_ylabel("F(x) / mm")
    ax[2].set_title(f"(c) profile, area {result.area_mm2 / 1e4:.3f} dm$^2$")
    ax[2].legend(fontsize=7)
    for a in ax[:2]:
        a.set_axis_off()
    fig.suptitle(title or Path(result.path).name)
    fig.tight_layout()
    return _save(fig, stem)
