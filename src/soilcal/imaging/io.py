"""Reading photos: any file PIL can decode completely; anything else is an InputError.

Every colour mode PIL reads is accepted: RGB, CMYK, palette, with or without alpha (the alpha
channel is dropped), 1-bit, 8-bit grey, and single-channel 16-bit or 32-bit frames (PIL modes
``I;16``, ``I``, ``F``; a grey + alpha PNG of 16 bits per sample, which PIL reads at 8 bits, is
read at its 16 bits, :func:`_grey_alpha16`), which are scaled by their bit depth and stretched between their 0.5
and 99.5 percentiles instead of being clipped to 8 bits.  A colour photo of 16 bits per channel
(PNG or TIFF) is read at its 16 bits (PIL keeps only the upper 8 of them: :func:`_deep_rgb`) and
scaled by the bit depth its values use (65535 for a full-range photo, 4095 for a 12-bit camera's
values in a 16-bit file: a PNG's sBIT chunk where it says it, else the depth holding 99.9 % of
its values, so that a hot pixel does not set it), so it reads like its 8-bit version.  A TIFF
of more than 8 bits per sample with its planes stored apart (planar configuration), which PIL
decodes as 8-bit samples, is read at its depth with ``tifffile`` (:func:`_tiff_decode`).  A photo with an EXIF Orientation
tag (a phone held upright or upside down) is turned as a viewer shows it before it is measured.
A HEIC or HEIF photo (an iPhone's default format) is read through ``pillow-heif``
(:func:`_heif_opener`), which turns it as it is shown (the rotation the file stores, its EXIF
orientation then 1); where that package cannot be imported, such a photo is refused naming it.
:func:`read_photo_reduced` and :func:`read_gray_reduced` decode a large photo reduced by a whole
factor (a JPEG in its decoder), so it is never held at full size as floats.  A colour photo
must span an eighth of its grey levels (:data:`MIN_GREY_LEVELS` of 256 at 8 bits).  A photo may have at most
:data:`MAX_PIXELS` pixels (a larger one is refused before it is decoded: scale it down).
"""

from __future__ import annotations

import functools
import math
import warnings
from pathlib import Path

import numpy as np

#: the largest photo read, in pixels (64 megapixels, e.g. 9600 x 6666): a float RGB copy of
#: it takes 1.5 GB
MAX_PIXELS = 64_000_000

#: the fewest grey levels (of 256) a photo's luminance must span between its 0.5 and 99.5
#: percentiles: one spanning an eighth of the range or less (under- or over-exposed) gave heap
#: angles 3 to 7 deg off as if they were sound.  A 16-bit colour photo must span as large a
#: share of the levels its bit depth has (an eighth): its levels are fine, but a plate edge
#: and flanks of an eighth of the contrast are as faint as in the 8-bit photo
MIN_GREY_LEVELS = 32

# full scale of PIL's single-channel modes; RGB-like modes go through luminance
_FULL_SCALE = {"1": 1.0, "L": 255.0, "I;16": 65535.0, "I;16L": 65535.0, "I;16B": 65535.0, "I;16N": 65535.0}
_HIGH_DEPTH = ("I;16", "I;16L", "I;16B", "I;16N", "I", "F")
#: the mode :func:`_decode` gives a colour photo of 16 bits per channel read at 8 bits (its
#: low bytes not decodable), as against one read at 16 bits whose values use 8 bits ("RGB;16")
_DEEP_AT_8 = "RGB;16 read at 8 bits"


def _stretch(g: np.ndarray) -> np.ndarray:
    lo, hi = np.percentile(g, [0.5, 99.5])
    return np.clip((g - lo) / (hi - lo), 0.0, 1.0) if hi - lo > 0 else np.zeros_like(g)


def _with_args(tile, args):
    """PIL decoder ``tile`` (decoder, extents, offset, args) with other decoder ``args``: a
    tile is a plain 4-tuple before Pillow 11 and a NamedTuple (``ImageFile._Tile``) from it on,
    so it is read by position and rebuilt as the type Pillow uses."""
    from PIL import ImageFile

    make = getattr(ImageFile, "_Tile", None)
    return make(tile[0], tile[1], tile[2], args) if make is not None else (tile[0], tile[1], tile[2], args)


def _other_bytes(tile):
    """``tile`` decoding the other byte of each 16-bit sample: its raw mode's byte order
    swapped (big- for little-endian, native for the other one), so PIL's unpacker, which keeps
    one byte of each sample, keeps the low byte instead of the high one; None when its raw
    mode is not a 16-bit RGB(A) one PIL can unpack either way."""
    import sys

    args = tile[3]
    raw = args if isinstance(args, str) else args[0] if isinstance(args, tuple) and args else None
    if not isinstance(raw, str) or not raw.startswith(("RGB;16", "RGBA;16", "RGBX;16")) or raw[-1] not in "BLN":
        return None
    order = raw[-1] if raw[-1] != "N" else ("L" if sys.byteorder == "little" else "B")
    swapped = raw[:-1] + ("B" if order == "L" else "L")
    return _with_args(tile, swapped if isinstance(args, str) else (swapped,) + tuple(args[1:]))


def _deep_rgb(p: Path, hi):
    """The 16-bit RGB values (uint16, rows x columns x 3) of the colour photo ``p`` of 16 bits
    per channel, of which PIL decoded the upper bytes into ``hi`` (loaded, turned as shown);
    None when its low bytes cannot be decoded (then it is read at 8 bits).  The photo is decoded
    a second time with each sample's bytes swapped (:func:`_other_bytes`): PIL's own decoders
    (PNG filters, TIFF compressions) keep the low bytes then."""
    from PIL import Image, ImageOps

    with Image.open(p) as im:
        tiles = [_other_bytes(t) for t in im.tile]
        if not tiles or any(t is None for t in tiles):
            return None
        im.tile = tiles
        im.load()
        lo = ImageOps.exif_transpose(im)
        if lo.size != hi.size or lo.mode != hi.mode:
            return None
        out = np.empty((hi.size[1], hi.size[0], 3), np.uint16)
        for k in range(3):
            out[..., k] = np.asarray(hi.getchannel(k), np.uint16) << 8 | np.asarray(lo.getchannel(k), np.uint16)
        return out


def _raw_mode(tile):
    """The raw mode a PIL decoder tile (decoder, extents, offset, args) unpacks (None if it
    names none)."""
    args = tile[3]
    raw = args if isinstance(args, str) else args[0] if isinstance(args, tuple) and args else None
    return raw if isinstance(raw, str) else None


def _grey_alpha16(im):
    """The 16-bit grey values (uint16, rows x columns, turned as shown) of the grey + alpha PNG
    of 16 bits per sample opened as ``im`` (not loaded), whose grey PIL reads at its upper 8
    bits: decoded as raw 4-byte pixels (raw mode RGBA, the 4 bytes per pixel the PNG's filters
    work on), the grey's big-endian bytes are its first two."""
    from PIL import ImageOps

    im.tile = [_with_args(t, "RGBA" if isinstance(t[3], str) else ("RGBA",) + tuple(t[3][1:])) for t in im.tile]
    im.load()
    a = np.asarray(ImageOps.exif_transpose(im))
    return a[..., 0].astype(np.uint16) << 8 | a[..., 1].astype(np.uint16)


#: the share of a 16-bit photo's values (per channel sample) that its bit depth is estimated
#: from where the file does not say it: the depth holding this percentile of them, so that a
#: hot pixel or a specular glint (a few samples at the top of the range) does not set it
DEPTH_PERCENTILE = 99.9


def _png_significant_bits(p: Path):
    """The bits per colour channel a PNG's sBIT chunk says its samples hold (the largest of its
    colour channels'), or None: no PNG, or none given."""
    import struct

    try:
        with open(p, "rb") as fh:
            if fh.read(8) != b"\x89PNG\r\n\x1a\n":
                return None
            colour_type = None
            while True:
                head = fh.read(8)
                if len(head) < 8:
                    return None
                n, kind = struct.unpack(">I4s", head)
                if kind in (b"IDAT", b"IEND"):
                    return None
                data = fh.read(n)
                fh.read(4)  # CRC
                if kind == b"IHDR" and n >= 10:
                    colour_type = data[9]
                elif kind == b"sBIT" and data:
                    colour = data[:3] if colour_type in (2, 3, 6) else data[:1]
                    bits = max(colour)
                    return bits if 1 <= bits <= 16 else None
    except OSError:
        return None


def _bit_depth_scaled(v: np.ndarray, f: int, bits=None):
    """16-bit values ``v`` reduced by ``f`` (box averages, as :meth:`PIL.Image.Image.reduce`)
    and scaled to [0, 1] by the bit depth they use: ``bits`` where the file says it (a PNG's
    sBIT chunk; by 65535 where the values are scaled to the file's 16 bits, as the standard
    has them, and exceed that depth), else the smallest of 8 to 16 bits holding their
    :data:`DEPTH_PERCENTILE` percentile (a 12-bit camera's values in a 16-bit file by 4095,
    whatever a hot pixel holds); values above it are clipped.  Returns (image, levels of that
    depth)."""
    from PIL import Image

    if f >= 2:
        v = np.stack([np.asarray(Image.fromarray(v[..., k].astype(np.int32), "I").reduce(f), float)
                      for k in range(v.shape[-1])], axis=-1)
    top = float(np.percentile(v, DEPTH_PERCENTILE))
    if bits is None:
        bits = max(8, int(np.ceil(np.log2(top + 1.0))))
    elif top > 2.0 ** bits - 1.0:
        # the values scaled to the file's 16 bits, as the PNG standard has them (the low bits
        # padding): scaled by 65535, their levels those of the significant bits
        return np.asarray(v, float) / 65535.0, 2 ** bits
    return np.minimum(np.asarray(v, float) / (2.0 ** bits - 1.0), 1.0), 2 ** bits


def _reduction(w: int, h: int, min_pixels) -> int:
    """The largest whole factor a ``w`` x ``h`` photo can be reduced by keeping at least
    ``min_pixels`` (1: none, or no ``min_pixels``)."""
    return max(1, math.isqrt(w * h // min_pixels)) if min_pixels else 1


#: the shown axes (x, y) an EXIF orientation's turn reverses against the stored ones (a stored
#: axis's last pixel, which a whole-factor reduction leaves partial, comes first on those)
_REVERSED = {2: (True, False), 3: (True, True), 4: (False, True), 6: (True, False), 7: (True, True),
             8: (False, True)}


#: the brands of an ISO base media file's ``ftyp`` box that make it a HEIF still image (HEIC
#: from a phone: heic, heix, mif1; sequences and AVIF are HEIF too)
_HEIF_BRANDS = (b"heic", b"heix", b"heim", b"heis", b"hevc", b"hevx", b"mif1", b"msf1", b"avif", b"avis")


def _is_heif(p: Path) -> bool:
    """Whether the file starts as a HEIF image does (an ``ftyp`` box of a HEIF brand)."""
    try:
        with open(p, "rb") as f:
            head = f.read(12)
    except OSError:
        return False
    return len(head) == 12 and head[4:8] == b"ftyp" and head[8:12] in _HEIF_BRANDS


@functools.cache
def _heif_opener() -> bool:
    """Register ``pillow-heif``'s HEIF opener with PIL (once); False where it cannot be imported."""
    try:
        import pillow_heif
    except ImportError:
        return False
    pillow_heif.register_heif_opener()
    return True


def _decode(path, formats: str, min_pixels=None, geometry=None):
    """(PIL mode, grey [0, 1] for single-channel modes else None, RGB [0, 1] else None, (width,
    height) as shown, grey levels of the photo's depth: 256 for 8 bits per channel).  A colour
    photo of 16 bits per channel has mode "RGB;16" and is read at its 16 bits where PIL can
    decode its low bytes (:func:`_deep_rgb`, scaled by :func:`_bit_depth_scaled`; else mode
    :data:`_DEEP_AT_8`, at 8 bits).  With
    ``min_pixels``, a photo of more pixels is decoded reduced by a whole factor that keeps at
    least that many: a JPEG in its decoder (DCT scaling, by 2, 4 or 8,
    :meth:`PIL.Image.Image.draft`), any photo by box averaging (:meth:`PIL.Image.Image.reduce`)
    before it is turned into floats, so a phone's 12 or 48 megapixels are never held at full
    size as floats."""
    from PIL import Image, ImageOps, UnidentifiedImageError

    from soilcal.errors import InputError

    p = Path(path)
    if not p.is_file():
        raise InputError(p, "file", "an existing image file", "a folder" if p.is_dir() else "missing")
    expected = f"a complete, readable image ({formats})"
    if _is_heif(p) and not _heif_opener():
        raise InputError(p, "file", expected + "; a HEIC or HEIF photo needs the package pillow-heif "
                         "(pip install pillow-heif), or export it as JPEG", "a HEIF image, pillow-heif not installed")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", Image.DecompressionBombWarning)
            with Image.open(p) as im:
                w, h = im.size
                if w * h > MAX_PIXELS:
                    raise InputError(p, "file", f"an image of at most {MAX_PIXELS // 1_000_000} megapixels "
                                     "(scale it down)", f"{w} x {h} pixels")
                if im.format == "TIFF" and im.tag_v2.get(284) == 2:
                    bits = im.tag_v2.get(258, (8,))
                    if max(bits if isinstance(bits, tuple) else (bits,)) > 8:
                        # planes stored apart at more than 8 bits: PIL decodes the bytes of
                        # each plane as 8-bit samples (a photo of noise, read without a
                        # complaint); read at its depth by tifffile
                        tiff = _tiff_decode(p, min_pixels)
                        if tiff is None:
                            raise InputError(p, "file", expected + ", its planes of more than 8 bits readable",
                                             "a planar TIFF that could not be decoded")
                        return tiff
                if im.format == "PNG" and im.tile and all(_raw_mode(t) == "LA;16B" for t in im.tile):
                    # grey + alpha of 16 bits per sample: PIL opens it as RGBA of the grey's
                    # upper 8 bits, which a 12-bit camera's values hardly use (refused as a
                    # blank or flat photo that read without the alpha is measured)
                    g16 = _grey_alpha16(im)
                    shown = (w, h) if (g16.shape[1] > g16.shape[0]) == (w > h) else (h, w)
                    f = _reduction(g16.shape[1], g16.shape[0], min_pixels)
                    g16 = Image.fromarray(g16.astype(np.int32), "I")
                    g16 = g16.reduce(f) if f >= 2 else g16
                    return "I;16", np.asarray(g16, float) / 65535.0, None, shown, 65536
                # a colour photo of 16 bits per channel: PIL keeps the upper 8 of them (the
                # lower 8 are decoded apart, _deep_rgb)
                deep = im.mode not in _FULL_SCALE and im.mode not in ("I", "F") and any(
                    ";16" in str(t[3]) for t in im.tile)
                f = _reduction(w, h, min_pixels)
                if f >= 2 and im.format in ("JPEG", "MPO"):  # MPO: a phone's JPEG with a multi-picture block
                    im.draft(None, (-(-w // f), -(-h // f)))  # decoded at 1/2, 1/4 or 1/8 size
                im.load()  # decodes fully: a truncated JPEG raises OSError here
                # the JPEG decoder's factor d (1, 2, 4 or 8): ceil(n / d) pixels a side, the last
                # one partial where d does not divide n
                dw, dh = im.size
                d = next((k for k in (1, 2, 4, 8) if (-(-w // k), -(-h // k)) == (dw, dh)), 1)
                orient = im.getexif().get(0x0112, 1)
                # a phone stores a portrait (or upside-down) photo in the sensor's orientation
                # and says how to turn it in its EXIF Orientation tag: turned as it is shown
                im = ImageOps.exif_transpose(im)
                shown = (w, h) if (im.size[0] > im.size[1]) == (w > h) else (h, w)
                mode = im.mode
                f = _reduction(*im.size, min_pixels)
                if geometry is not None:
                    # a shown axis reversed from a stored one has the decoder's partial pixel
                    # first: its pixels start (ceil(n / d) - n / d) of one later
                    stored = (h, w) if orient in (5, 6, 7, 8) else (w, h)
                    rev = _REVERSED.get(orient, (False, False))
                    geometry["factor"] = d * f
                    geometry["offset"] = tuple((-(-n // d) - n / d) / f if r else 0.0 for n, r in zip(stored, rev))
                v = _deep_rgb(p, im) if deep and mode in ("RGB", "RGBA") else None
                if v is not None:
                    sbit = _png_significant_bits(p)  # None but for a PNG saying it
                    rgb, depth = _bit_depth_scaled(v, f, sbit)
                    return "RGB;16", None, rgb, shown, depth
                if mode not in _FULL_SCALE and mode not in ("I", "F"):
                    im = im.convert("RGB")
                if f >= 2:
                    # 1-bit as 0 or 255 and 16-bit as 32-bit integers, which reduce averages
                    im = (im.convert("L") if mode == "1" else im.convert("I") if mode.startswith("I;16") else im).reduce(f)
                if mode in ("I", "F"):
                    g = np.asarray(im, dtype=float)
                    top = 65535.0 if mode == "I" and g.min() >= 0 and g.max() <= 65535 else max(float(np.abs(g).max()), 1e-12)
                    return mode, g / top, None, shown, 65536
                if mode in _FULL_SCALE:
                    top = 255.0 if im.mode == "L" else _FULL_SCALE[mode]
                    return mode, np.asarray(im, dtype=float) / top, None, shown, 256
                # a 16-bit colour photo whose low bytes could not be decoded: read at 8 bits
                return (_DEEP_AT_8 if deep else mode), None, np.asarray(im, dtype=float) / 255.0, shown, 256
    except InputError:
        raise
    except Image.DecompressionBombError as exc:
        raise InputError(p, "file", f"an image of at most {MAX_PIXELS // 1_000_000} megapixels (scale it down)",
                         str(exc).split(" exceeds")[0]) from None
    except UnidentifiedImageError as exc:
        tiff = _tiff_decode(p, min_pixels)  # a TIFF PIL cannot open (its planes stored apart)
        if tiff is not None:
            return tiff
        raise InputError(p, "file", expected, str(exc) or type(exc).__name__) from None
    except (OSError, SyntaxError, ValueError, EOFError, MemoryError) as exc:
        raise InputError(p, "file", expected, str(exc) or type(exc).__name__) from None


def _tiff_decode(p: Path, min_pixels=None):
    """:func:`_decode`'s tuple for a TIFF that PIL cannot open, read with ``tifffile``: a
    planar-configuration TIFF (each colour plane stored apart, as scientific cameras and image
    editors write them) of 8 or 16 bits per sample, grey or RGB (an alpha sample dropped), read
    at its own depth as PIL's own TIFFs are; None when the file is no TIFF or tifffile cannot
    read it either.  One with an EXIF orientation other than upright is refused (its turn is
    not applied here)."""
    from soilcal.errors import InputError

    try:
        with open(p, "rb") as fh:
            if fh.read(4) not in (b"II*\x00", b"MM\x00*"):
                return None
        import tifffile

        with tifffile.TiffFile(p) as tf:
            page = tf.pages[0]
            orient = page.tags.get(274)
            a = page.asarray()
            axes = tf.series[0].axes
    except Exception:  # noqa: BLE001 - any failure of the second reader: the first one's refusal stands
        return None
    if orient is not None and orient.value != 1:
        raise InputError(p, "file", "a TIFF stored upright (EXIF orientation 1), or saved upright by an editor",
                         f"orientation {orient.value}")
    if a.ndim == 3 and axes.startswith("S"):
        a = np.moveaxis(a, 0, -1)
    if a.dtype not in (np.uint8, np.uint16) or not (a.ndim == 2 or (a.ndim == 3 and a.shape[-1] in (1, 2, 3, 4))):
        raise InputError(p, "file", "a TIFF of 8 or 16 bits per sample, grey or RGB (with or without alpha)",
                         f"{a.dtype} samples, shape {a.shape}")
    if a.ndim == 3:
        a = a[..., :1] if a.shape[-1] <= 2 else a[..., :3]  # alpha dropped
        a = a[..., 0] if a.shape[-1] == 1 else a
    h, w = a.shape[:2]
    if w * h > MAX_PIXELS:
        raise InputError(p, "file", f"an image of at most {MAX_PIXELS // 1_000_000} megapixels (scale it down)",
                         f"{w} x {h} pixels")
    f = _reduction(w, h, min_pixels)
    if a.ndim == 3 and a.dtype == np.uint16:
        rgb, depth = _bit_depth_scaled(a, f)
        return "RGB;16", None, rgb, (w, h), depth
    v = np.asarray(a, float)
    if f >= 2:
        hh, ww = h // f * f, w // f * f
        v = v[:hh, :ww].reshape(hh // f, f, ww // f, f, *v.shape[2:]).mean(axis=(1, 3))
    if a.ndim == 2:
        return ("L", v / 255.0, None, (w, h), 256) if a.dtype == np.uint8 else ("I;16", v / 65535.0, None, (w, h), 65536)
    return "RGB", None, v / 255.0, (w, h), 256


def read_photo(path) -> np.ndarray:
    """RGB float image in [0, 1]; unreadable, truncated or blank files raise InputError."""
    return read_photo_reduced(path)[0]


def read_photo_reduced(path, min_pixels=None, with_depth=False, with_map=False):
    """(:func:`read_photo`'s image, (width, height) of the photo as shown), and with
    ``with_depth`` the grey levels of the depth it was read at (256 at 8 bits per channel, 4096
    for a 12-bit camera's values in a 16-bit file) as a third item, and with ``with_map`` too
    (factor, (offset x, offset y)) as a fourth: the image's pixel at column (c + 0.5) / factor
    - 0.5 + offset x (rows alike) is the photo's at c as shown (a side not divisible by the
    factor ends in a partial pixel, first on an axis the EXIF orientation reverses after a JPEG
    was decoded reduced); with ``min_pixels``
    a larger photo comes reduced by the largest whole factor keeping at least that many pixels
    (decoded reduced where the format allows: :func:`_decode`).  A colour photo whose luminance
    spans less than an eighth of its grey levels (between its 0.5 and 99.5 percentiles; fewer
    than :data:`MIN_GREY_LEVELS` of 256 at 8 bits per channel) is refused: its edges are
    quantisation steps, or too faint, which the plate and flank searches take for lines or miss."""
    from skimage.color import rgb2gray

    from soilcal.errors import InputError

    p = Path(path)
    geometry = {}
    mode, g, rgb, shown, depth = _decode(p, "JPEG/PNG/TIFF/HEIC", min_pixels, geometry)
    if rgb is None:
        if mode in _HIGH_DEPTH:
            g = _stretch(g)
        rgb = np.repeat(g[..., None], 3, axis=-1)
    if rgb.ndim != 3 or min(rgb.shape[:2]) < 64:
        raise InputError(p, "file", "an image of at least 64 x 64 pixels", f"{rgb.shape[1]} x {rgb.shape[0]} pixels")
    if float(rgb.reshape(-1, rgb.shape[-1]).std(axis=0).max()) < 0.01:  # no channel varies over the pixels
        raise InputError(p, "image", "a photo with contrast (heap against background)", "a blank image")
    if mode not in _HIGH_DEPTH:
        lo, hi = np.percentile(rgb2gray(rgb), [0.5, 99.5])
        levels = (hi - lo) * (depth - 1)
        if levels < MIN_GREY_LEVELS * depth / 256:
            why = ("a 16-bit colour photo read at 8 bits per channel (save it as 8- or 16-bit RGB)"
                   if mode == _DEEP_AT_8 else
                   "too little brightness contrast between heap, plate and wall: an under- or over-exposed photo, "
                   "or a heap and a wall alike in brightness")
            raise InputError(p, "image", f"a photo whose brightness spans at least {MIN_GREY_LEVELS * depth // 256} of "
                             f"its {depth} grey levels (heap, plate and wall exposed)", f"{levels:.0f} levels: {why}")
    if not with_depth:
        return rgb, shown
    if with_map:
        # every reader but the JPEG decoder's reduces as shown: a whole factor, no offset
        factor = geometry.get("factor", max(1, round(shown[0] / rgb.shape[1])))
        return rgb, shown, depth, (factor, geometry.get("offset", (0.0, 0.0)))
    return rgb, shown, depth


def read_gray(path):
    """(grey image in [0, 1], RGB view for figures) of any PIL-readable frame
    (:func:`read_gray_reduced` at full size).

    Single-channel 8-bit and 16-bit frames (BMP/PNG/TIFF, PIL modes L, I;16, I) are scaled
    by their bit depth and not converted through RGB (which would clip 16-bit data); colour
    images give their luminance.  The grey range is then stretched between its 0.5 and 99.5
    percentiles, so a 12-bit camera in a 16-bit container reads like any other frame.
    """
    return read_gray_reduced(path)[:2]


def read_gray_reduced(path, min_pixels=None):
    """(:func:`read_gray`'s grey image and RGB view, (width, height) of the frame as shown); with
    ``min_pixels`` a larger frame comes reduced by the largest whole factor keeping at least
    that many pixels (a JPEG decoded reduced: :func:`_decode`)."""
    from skimage.color import rgb2gray

    from soilcal.errors import InputError

    p = Path(path)
    mode, g, rgb, shown, _ = _decode(p, "BMP/PNG/TIFF/JPEG/HEIC", min_pixels)
    if g is None:
        g = rgb2gray(rgb)
    if g.ndim != 2 or min(g.shape) < 64:
        raise InputError(p, "file", "an image of at least 64 x 64 pixels", f"{g.shape[-1]} x {g.shape[0]} pixels")
    lo, hi = np.percentile(g, [0.5, 99.5])
    if hi - lo < 0.005:
        raise InputError(p, "image", "a frame with contrast (powder against air)", "a blank image")
    g = np.clip((g - lo) / (hi - lo), 0.0, 1.0)
    return g, (rgb if rgb is not None else np.repeat(g[..., None], 3, axis=-1)), shown
