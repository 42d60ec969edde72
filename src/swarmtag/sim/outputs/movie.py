"""Movie files from RGBA frames: a GIF with one shared palette (Pillow), an MP4 through ffmpeg.

The GIF's palette is chosen once, from sampled frames, so every frame maps
a colour to the same index: the still background stays byte-identical from
frame to frame, Pillow stores only each frame's changed rectangle (its
unchanged pixels transparent), and the file stays small. Without dithering
a flat colour stays flat. ``GifDrawing`` takes the frames as an animation
draws them (the palette's first); ``write_gif_drawn`` writes it in a forked
process while they are drawn (``swarmtag._beside``), where it can.
"""

# Pillow and matplotlib come with the ``plot`` extra: their imports are deferred to first use.
# ruff: noqa: PLC0415

from __future__ import annotations

import os
import subprocess
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass
from typing import Any, Final

import numpy as np
from numpy.typing import NDArray

from swarmtag._beside import beside
from swarmtag.errors import ConfigError

__all__ = [
    "PALETTE_SAMPLES",
    "GifDrawing",
    "gif_indices",
    "gif_palette",
    "require_ffmpeg",
    "write_gif",
    "write_mp4",
]

PALETTE_SAMPLES: Final = 8
"""Most frames (evenly spaced, first and last included) whose colours choose a GIF's palette."""
_COLOURS: Final = 255
"""Palette entries used; the 256th is left free for Pillow to mark unchanged pixels transparent."""
_EXACT: Final = 128
"""Palette entries for the samples' most frequent colours, reproduced exactly."""


def _packed(rgb: NDArray[np.integer[Any]]) -> NDArray[np.uint32]:
    """RGB triples (rows of a palette) as 24-bit keys ``R | G << 8 | B << 16``."""
    wide = rgb.astype(np.uint32)
    return (wide[..., 0] | (wide[..., 1] << 8) | (wide[..., 2] << 16)).astype(np.uint32)


def _frame_keys(frame: NDArray[np.uint8]) -> NDArray[np.uint32]:
    """An RGBA frame's pixels as ``_packed`` keys: its bytes read as little-endian words."""
    if frame.dtype != np.uint8 or frame.ndim != 3 or frame.shape[2] != 4:
        msg = f"a frame is RGBA bytes, shape (height, width, 4), not {frame.dtype} {frame.shape}"
        raise ValueError(msg)
    words: NDArray[np.uint32] = np.ascontiguousarray(frame).view(np.dtype("<u4"))[..., 0]
    return np.bitwise_and(words, np.uint32(0xFFFFFF))


def _unpacked(keys: NDArray[np.uint32]) -> NDArray[np.uint8]:
    """``_packed`` keys back to rows of RGB."""
    shifts = np.array([0, 8, 16], dtype=np.uint32)
    return ((keys[:, None] >> shifts) & 0xFF).astype(np.uint8)


def gif_palette(
    samples: Sequence[NDArray[np.uint8]], keep: Iterable[tuple[int, int, int]] = ()
) -> NDArray[np.uint8]:
    """At most 255 colours for the RGBA ``samples``, as rows of RGB: exact fills, then coverage.

    First ``keep`` (colours to hold even if the samples lack them: the
    urgency colours a carrier may reach later on) and the colours most
    frequent in the samples, up to ``_EXACT``: the flat fills (background,
    areas, bodies, text), which so come out exact. The rest of the palette
    covers the other pixels (anti-aliased edges, thin translucent lines)
    by Pillow's octree quantiser, so a faint blue circle stays blue.
    Deterministic: ties in frequency go to the lower colour.
    """
    from PIL import Image

    keys = np.concatenate([_frame_keys(frame).ravel() for frame in samples])
    colours, counts = np.unique(keys, return_counts=True)
    frequent = colours[np.lexsort((colours, -counts))]  # most frequent first, then lowest
    kept = _packed(np.array(list(keep), dtype=np.uint8).reshape(-1, 3)).tolist()
    chosen = list(dict.fromkeys([*kept, *frequent[:_EXACT].tolist()]))[:_EXACT]
    rest = ~np.isin(colours, np.array(chosen, dtype=np.uint32))
    others = np.repeat(colours[rest], counts[rest])  # the other pixels, sorted by colour
    if others.size:
        room = _COLOURS - len(chosen)
        octree = Image.fromarray(_unpacked(others)[None]).quantize(
            colors=room, method=Image.Quantize.FASTOCTREE, dither=Image.Dither.NONE
        )
        entries = np.array(octree.getpalette() or [], dtype=np.uint8).reshape(-1, 3)[:room]
        chosen = list(dict.fromkeys([*chosen, *_packed(entries).tolist()]))
    return _unpacked(np.array(chosen[:_COLOURS], dtype=np.uint32))


def gif_indices(
    frames: Iterable[NDArray[np.uint8]], palette: NDArray[np.uint8]
) -> Iterator[NDArray[np.uint8]]:
    """Each RGBA frame as indices into ``palette``: exact where it holds the colour, else nearest.

    Pillow's own mapping onto a given palette is approximate (a reduced
    colour cube): it would turn white into a near-white and speckle flat
    areas. Nearest is the least squared RGB distance, the lower index on
    ties; a table over all 2^24 colours (16 MiB) remembers each colour met.
    """
    if not 0 < len(palette) <= _COLOURS:
        msg = f"a GIF palette holds 1 to {_COLOURS} colours, not {len(palette)}"
        raise ValueError(msg)
    unknown = _COLOURS  # an index no palette entry has
    table = np.full(1 << 24, unknown, dtype=np.uint8)
    table[_packed(palette)] = np.arange(len(palette), dtype=np.uint8)  # distinct colours
    reference = palette.astype(np.int32)
    for frame in frames:
        keys = _frame_keys(frame)
        index = table[keys]
        if index.max() == unknown:  # colours not met before
            new = index == unknown
            missing, inverse = np.unique(keys[new], return_inverse=True)
            rgb = _unpacked(missing).astype(np.int32)
            distance = ((rgb[:, None, :] - reference[None, :, :]) ** 2).sum(axis=2)
            nearest = np.argmin(distance, axis=1).astype(np.uint8)
            table[missing] = nearest
            index[new] = nearest[inverse]
        yield index


def write_gif(
    frames: Iterable[NDArray[np.uint8]],
    path: str | os.PathLike[str],
    *,
    palette: NDArray[np.uint8],
    fps: int,
) -> None:
    """Write RGBA ``frames`` (opaque) as a looping GIF at ``fps``, every frame through ``palette``.

    Pillow stores each frame after the first as the rectangle that changed,
    its unchanged pixels transparent (``optimize``: long runs compress well).
    It merges a frame identical to the one before into it (longer duration);
    the frames of a run differ at least in their titles' ticks.
    """
    from PIL import Image

    flat = palette.tobytes()

    def images() -> Iterator[Image.Image]:
        for indices in gif_indices(frames, palette):
            image = Image.fromarray(indices)
            image.putpalette(flat)
            yield image

    stream = images()
    first = next(stream)
    first.save(
        os.fspath(path),
        format="GIF",
        save_all=True,
        append_images=stream,
        duration=int(1000 / fps),
        loop=0,
        optimize=True,
    )


@dataclass(frozen=True)
class GifDrawing:
    """A GIF of ``count`` frames as they are drawn: the palette's samples first, then the rest.

    ``sampled`` are the positions (in the GIF) of the frames that choose the
    palette (``gif_palette``, holding ``keep``); the drawing gives those
    first, then every other frame in order. ``write`` writes what
    ``write_gif`` would write from the frames in order, byte for byte.
    """

    path: str
    count: int
    keep: tuple[tuple[int, int, int], ...]
    fps: int

    @property
    def sampled(self) -> tuple[int, ...]:
        """The palette's frames: at most ``PALETTE_SAMPLES``, evenly spaced, first and last."""
        spaced = np.linspace(0, self.count - 1, min(self.count, PALETTE_SAMPLES))
        return tuple(int(i) for i in np.unique(spaced.round()))

    def drawing_order(self) -> list[int]:
        """The GIF's frame positions in the order the drawing gives them."""
        sampled = self.sampled
        return [*sampled, *(i for i in range(self.count) if i not in sampled)]

    def write(self, drawn: Iterable[NDArray[np.uint8]]) -> None:
        """Write the GIF from the RGBA frames ``drawn`` in ``drawing_order``."""
        frames = iter(drawn)
        samples = {position: next(frames) for position in self.sampled}
        palette = gif_palette(list(samples.values()), keep=self.keep)
        in_order = (samples.pop(i) if i in samples else next(frames) for i in range(self.count))
        write_gif(in_order, self.path, palette=palette, fps=self.fps)

    def prepare(self) -> None:
        """Nothing to load first (a ``swarmtag._beside.Job``)."""

    def finish(self, items: Iterable[Any], step: Callable[[str], None]) -> list[str]:
        """``write`` from the frames sent (a ``swarmtag._beside.Job``); no notes."""
        self.write(items)
        return []


def write_gif_drawn(gif: GifDrawing, drawn: Iterable[NDArray[np.uint8]]) -> None:
    """Write ``gif`` from ``drawn``, in a forked process beside the drawing where one can fork.

    The palette, the indices and Pillow's compression (about a third of an
    animation's time) then run on another core while the frames are drawn.
    """
    with beside(gif) as writers:
        if not writers:
            gif.write(drawn)
            return
        (writer,) = writers
        for frame in drawn:
            writer.send(frame, _unreported)
        writer.finish(_unreported)


def _unreported(_step: str) -> None:
    """The GIF's writer reports no steps."""


def require_ffmpeg() -> str:
    """The ffmpeg executable to use, or a ``ConfigError`` saying how to get one.

    Matplotlib's (``ffmpeg`` on the PATH, or ``rcParams["animation.ffmpeg_path"]``)
    if there is one, else the one the ``imageio-ffmpeg`` package ships.
    """
    from matplotlib.animation import FFMpegWriter

    if FFMpegWriter.isAvailable():
        return str(FFMpegWriter.bin_path())
    try:
        import imageio_ffmpeg  # type: ignore[import-not-found, unused-ignore]
    except ImportError:
        msg = "MP4 animations need ffmpeg: pip install imageio-ffmpeg, or write a .gif"
        raise ConfigError(msg) from None
    return str(imageio_ffmpeg.get_ffmpeg_exe())


def write_mp4(
    frames: Iterable[NDArray[np.uint8]],
    path: str | os.PathLike[str],
    *,
    size: tuple[int, int],
    fps: int,
) -> None:
    """Pipe RGBA ``frames`` of ``size`` (width, height) to ffmpeg as an H.264 MP4 at ``fps``.

    The ffmpeg is ``require_ffmpeg``'s; H.264's 4:2:0 colour needs even
    sides, so an odd side is padded by one pixel.
    """
    width, height = size
    command = [
        require_ffmpeg(), "-f", "rawvideo", "-vcodec", "rawvideo",
        "-s", f"{width}x{height}", "-pix_fmt", "rgba", "-framerate", str(fps),
        "-loglevel", "error", "-i", "pipe:",
        "-vcodec", "h264", "-pix_fmt", "yuv420p",
        "-vf", "pad=width=ceil(iw/2)*2:height=ceil(ih/2)*2",
        "-f", "mp4", "-y", os.fspath(path),
    ]  # fmt: skip
    with subprocess.Popen(  # noqa: S603 - a fixed argument list, no shell
        command, stdin=subprocess.PIPE, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE
    ) as ffmpeg:
        assert ffmpeg.stdin is not None
        assert ffmpeg.stderr is not None
        try:
            for frame in frames:
                ffmpeg.stdin.write(np.ascontiguousarray(frame).tobytes())
        except BrokenPipeError:
            pass  # ffmpeg stopped early: its message and status follow
        finally:
            ffmpeg.stdin.close()
        errors = ffmpeg.stderr.read().decode(errors="replace").strip()
        if ffmpeg.wait() != 0:
            msg = f"ffmpeg could not write {os.fspath(path)!r}: {errors or 'no message'}"
            raise ConfigError(msg)
