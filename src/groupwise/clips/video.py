"""Encoding a behaviour's frames as an MP4 clip and a poster image, and probing the result.

A clip is H.264 in an MP4 container, yuv420p (the pixel format every browser decodes), with
the index (``moov``) before the media data (``+faststart``) so a browser can start playing
before the file has arrived, at the frame rate the clip's timing asks for (`clips.timing`: real
speed, a rate such as 31.25 passed to ffmpeg as the fraction 125/4), no audio, no metadata.
Encoding uses the ffmpeg binary bundled with imageio-ffmpeg (no system ffmpeg needed), x264 on
a single thread, each clip by its own encoder instance: then a clip's bytes depend only on its
frames and the encoder settings (x264's output differs between thread counts), so equal frames
give byte-identical files and the same content id in the clip store. `ClipEncoder` encodes a
batch of clips in one ffmpeg process (each still by its own encoder).

Costs on a 2-core machine: an ffmpeg process with x264 costs ~20 ms to start and finish; a
240×240 Hopper frame ~1.1 ms of CPU with the "ultrafast" preset (144 KB per 1 s clip),
1.4 ms with "superfast" (51 KB), 1.7 ms with "veryfast" (31 KB).
"""

import io
import math
import re
import subprocess
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path

import imageio_ffmpeg
import numpy as np
from PIL import Image

POSTER_FORMATS: dict[str, str] = {"jpg": "JPEG", "png": "PNG"}
"""Poster suffix → Pillow format name."""

DEFAULT_FPS = 30.0
"""Frame rate of a clip encoded without one (SPEC §1's 30 frames/s)."""


class VideoEncodingError(RuntimeError):
    """ffmpeg failed to encode a clip (the message ends with ffmpeg's own error)."""


@dataclass(frozen=True)
class VideoConfig:
    """How clips and posters are encoded."""

    preset: str = "ultrafast"
    """x264 preset; "ultrafast" is the cheapest to encode (pool preparation is on the
    critical path of every round); "superfast" costs ~30 % more CPU for a third of the bytes
    (module docstring)."""
    crf: int = 23
    """x264 constant rate factor (0 lossless … 51 worst); 23 is x264's default."""
    poster_format: str = "jpg"
    """Poster image kind, a key of `POSTER_FORMATS`."""
    poster_quality: int = 85
    """JPEG quality of posters (ignored for PNG)."""

    def __post_init__(self) -> None:
        if not 0 <= self.crf <= 51:
            raise ValueError(f"crf must be in 0..51, got {self.crf}")
        if self.poster_format not in POSTER_FORMATS:
            choices = sorted(POSTER_FORMATS)
            raise ValueError(f"unknown poster format {self.poster_format!r}; choose from {choices}")


@dataclass(frozen=True)
class VideoInfo:
    """What ffmpeg reports about an encoded clip."""

    codec: str  # e.g. "h264"
    pix_fmt: str  # e.g. "yuv420p"
    width: int
    height: int
    fps: float
    frames: int
    faststart: bool  # the "moov" index precedes the "mdat" media data


def check_frames(frames: np.ndarray) -> np.ndarray:
    """Validate a clip's frames: (L, H, W, 3) uint8, L >= 1, H and W even (yuv420p
    subsamples chroma 2×2). Returns them C-contiguous.

    Raises:
        ValueError: any of these does not hold.
    """
    frames = np.asarray(frames)
    if frames.ndim != 4 or frames.shape[-1] != 3 or frames.shape[0] < 1:
        raise ValueError(f"expected frames (L, H, W, 3), got {frames.shape}")
    if frames.dtype != np.uint8:
        raise ValueError(f"expected uint8 frames, got {frames.dtype}")
    if frames.shape[1] % 2 or frames.shape[2] % 2:
        raise ValueError(
            f"yuv420p needs an even frame size, got {frames.shape[2]}×{frames.shape[1]}"
        )
    return np.ascontiguousarray(frames)


def encode_mp4(
    frames: np.ndarray, path: Path, cfg: VideoConfig | None = None, fps: float = DEFAULT_FPS
) -> None:
    """Encode frames (F, H, W, 3) uint8 RGB as an H.264 yuv420p faststart MP4 at `path`,
    playing at `fps` frames per second.

    The file has exactly F frames. Raises ValueError for bad frames (`check_frames`) or
    frame rate, and VideoEncodingError when ffmpeg fails.
    """
    frames = check_frames(frames)
    _, height, width, _ = frames.shape
    with ClipEncoder([path], len(frames), width, height, cfg, fps) as encoder:
        for frame in frames:
            encoder.write(frame)


class ClipEncoder:
    """Encodes consecutive runs of `length` frames into one MP4 each, in one ffmpeg process.

    Write ``len(paths) * length`` frames (H, W, 3) uint8 in order: frames k·F … (k+1)·F − 1
    become ``paths[k]`` (F = `length`, frames per clip), played at `fps` frames per second.
    Each output has its own encoder, fed only its own frames (ffmpeg's trim filter), so a
    file is byte-identical to encoding its frames alone; one process per batch saves
    ffmpeg's start-up (~20 ms) per clip, and frames are encoded while the caller renders the
    next ones. Use as a context manager: leaving it waits for ffmpeg.

    Raises (from `write` or on exit):
        ValueError: a frame of the wrong shape or type.
        VideoEncodingError: ffmpeg failed, or fewer frames than promised were written.
    """

    def __init__(
        self,
        paths: Sequence[Path],
        length: int,
        width: int,
        height: int,
        cfg: VideoConfig | None = None,
        fps: float = DEFAULT_FPS,
    ) -> None:
        if not paths or length < 1:
            raise ValueError(f"need at least one output of >= 1 frames, got {len(paths)}, {length}")
        if width % 2 or height % 2:
            raise ValueError(f"yuv420p needs an even frame size, got {width}×{height}")
        self.paths = list(paths)
        self.length = length
        self.shape = (height, width, 3)
        self._expected = len(self.paths) * length
        self._written = 0
        cfg = cfg or VideoConfig()
        command = [
            imageio_ffmpeg.get_ffmpeg_exe(),
            "-hide_banner",
            "-nostdin",
            "-loglevel",
            "error",
            "-y",
            "-f",
            "rawvideo",
            "-pix_fmt",
            "rgb24",
            "-s",
            f"{width}x{height}",
            "-framerate",
            frame_rate(fps),
            "-i",
            "pipe:0",
        ]
        for k, path in enumerate(self.paths):
            command += [*_output_options(k * length, (k + 1) * length, cfg), str(path)]
        self._stderr = tempfile.TemporaryFile()
        self._process = subprocess.Popen(
            command, stdin=subprocess.PIPE, stdout=subprocess.DEVNULL, stderr=self._stderr
        )

    def __enter__(self) -> "ClipEncoder":
        return self

    def __exit__(self, kind: object, error: object, trace: object) -> None:
        self.close(failed=error is not None)

    def write(self, frame: np.ndarray) -> None:
        """Send the next frame (H, W, 3) uint8 to ffmpeg."""
        frame = np.asarray(frame)
        if frame.shape != self.shape or frame.dtype != np.uint8:
            raise ValueError(
                f"expected a {self.shape} uint8 frame, got {frame.shape} {frame.dtype}"
            )
        if self._written >= self._expected:
            raise ValueError(f"all {self._expected} frames were already written")
        assert self._process.stdin is not None
        try:
            self._process.stdin.write(np.ascontiguousarray(frame).tobytes())
        except BrokenPipeError:
            self._process.wait()
            raise VideoEncodingError(f"ffmpeg stopped early: {self._error_text()}") from None
        self._written += 1

    def close(self, failed: bool = False) -> None:
        """Finish the files and wait for ffmpeg (kill it when `failed`)."""
        if self._process.stdin is not None and not self._process.stdin.closed:
            try:
                self._process.stdin.close()
            except BrokenPipeError:
                pass
        if failed:
            self._process.kill()
        code = self._process.wait()
        message = self._error_text()
        self._stderr.close()
        if failed:
            return
        if code != 0:
            raise VideoEncodingError(f"ffmpeg could not encode {self.paths[0].name}: {message}")
        if self._written != self._expected:
            raise VideoEncodingError(f"{self._written} of {self._expected} frames were written")

    def _error_text(self) -> str:
        self._stderr.seek(0)
        return self._stderr.read().decode(errors="replace").strip()[-500:]


def frame_rate(fps: float) -> str:
    """`fps` as the fraction ffmpeg reads exactly, e.g. 31.25 → "125/4", 30 → "30/1".

    Raises:
        ValueError: not a positive finite rate.
    """
    if not math.isfinite(fps) or fps <= 0:
        raise ValueError(f"fps must be a positive number, got {fps}")
    rate = Fraction(fps).limit_denominator(1001)
    return f"{rate.numerator}/{rate.denominator}"


def _output_options(first: int, end: int, cfg: VideoConfig) -> list[str]:
    """ffmpeg options of one output: input frames first … end − 1, timestamps from 0."""
    return [
        "-map",
        "0:v",
        "-vf",
        f"trim=start_frame={first}:end_frame={end},setpts=PTS-STARTPTS",
        "-an",
        "-c:v",
        "libx264",
        "-preset",
        cfg.preset,
        "-crf",
        str(cfg.crf),
        "-pix_fmt",
        "yuv420p",
        # one encoder thread: x264's bitstream depends on its thread count
        "-threads",
        "1",
        "-movflags",
        "+faststart",
        "-map_metadata",
        "-1",
        "-fflags",
        "+bitexact",
        "-flags:v",
        "+bitexact",
        "-f",
        "mp4",
    ]


def poster_bytes(frame: np.ndarray, cfg: VideoConfig | None = None) -> bytes:
    """One (H, W, 3) uint8 frame encoded as a poster image (`VideoConfig.poster_format`)."""
    cfg = cfg or VideoConfig()
    image = Image.fromarray(np.ascontiguousarray(frame, dtype=np.uint8), mode="RGB")
    buffer = io.BytesIO()
    if cfg.poster_format == "jpg":
        image.save(buffer, format="JPEG", quality=cfg.poster_quality)
    else:
        image.save(buffer, format="PNG")
    return buffer.getvalue()


def poster_frame(length: int) -> int:
    """Index of the frame used as a clip's poster: the middle one."""
    return length // 2


_STREAM = re.compile(
    r"Stream #\S+.*?Video: (?P<codec>\w+).*?, (?P<pix>\w+)(?:\([^)]*\))?, "
    r"(?P<w>\d+)x(?P<h>\d+).*?(?P<fps>[\d.]+) fps"
)


def probe(path: Path) -> VideoInfo:
    """Codec, pixel format, size, frame rate, frame count and faststart of an MP4 file.

    Raises:
        VideoEncodingError: ffmpeg cannot read the file or it has no video stream.
    """
    command = [imageio_ffmpeg.get_ffmpeg_exe(), "-hide_banner", "-i", str(path)]
    result = subprocess.run(command, capture_output=True, check=False, text=True)
    match = _STREAM.search(result.stderr)
    if match is None:
        raise VideoEncodingError(f"no video stream in {path}: {result.stderr.strip()[-300:]}")
    frames, _ = imageio_ffmpeg.count_frames_and_secs(str(path))
    return VideoInfo(
        codec=match["codec"],
        pix_fmt=match["pix"],
        width=int(match["w"]),
        height=int(match["h"]),
        fps=float(match["fps"]),
        frames=int(frames),
        faststart=_moov_before_mdat(path),
    )


def read_frames(path: Path) -> np.ndarray:
    """Decode an MP4 file to RGB frames (L, H, W, 3) uint8."""
    reader = imageio_ffmpeg.read_frames(str(path), pix_fmt="rgb24")
    meta = next(reader)
    width, height = meta["size"]
    frames = [np.frombuffer(chunk, dtype=np.uint8).reshape(height, width, 3) for chunk in reader]
    return np.stack(frames)


def _moov_before_mdat(path: Path) -> bool:
    """Walk the top-level MP4 boxes: True when "moov" comes before "mdat"."""
    with open(path, "rb") as handle:
        while header := handle.read(8):
            if len(header) < 8:
                return False
            size = int.from_bytes(header[:4], "big")
            kind = header[4:8]
            if kind == b"moov":
                return True
            if kind == b"mdat":
                return False
            if size == 1:  # 64-bit size follows
                size = int.from_bytes(handle.read(8), "big") - 8
            elif size < 8:
                return False
            handle.seek(size - 8, io.SEEK_CUR)
    return False
