"""MP4 clips: exactly L frames, H.264 yuv420p with faststart, reproducible bytes; posters."""

import io
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from groupwise.clips.video import (
    ClipEncoder,
    VideoConfig,
    VideoEncodingError,
    encode_mp4,
    frame_rate,
    poster_bytes,
    probe,
    read_frames,
)


def _frames(length: int = 30, size: tuple[int, int] = (64, 48), seed: int = 0) -> np.ndarray:
    """A bright square moving across a dark background, one position per frame."""
    height, width = size
    frames = np.full((length, height, width, 3), 20, dtype=np.uint8)
    for k in range(length):
        x = (k * 3) % (width - 8)
        frames[k, 10:18, x : x + 8] = (230, 200, 40)
    return frames


def test_clip_has_exactly_l_frames_and_is_h264_yuv420p_faststart(tmp_path: Path) -> None:
    path = tmp_path / "clip.mp4"
    encode_mp4(_frames(30), path)
    info = probe(path)
    assert info.frames == 30
    assert (info.codec, info.pix_fmt) == ("h264", "yuv420p")
    assert (info.width, info.height) == (48, 64)
    assert info.fps == 30
    assert info.faststart


def test_frame_rate_and_length_follow_the_request(tmp_path: Path) -> None:
    path = tmp_path / "clip.mp4"
    encode_mp4(_frames(12), path, VideoConfig(preset="veryfast"), fps=24)
    info = probe(path)
    assert info.frames == 12 and info.fps == 24


@pytest.mark.parametrize(
    ("fps", "rate"), [(31.25, "125/4"), (20.0, "20/1"), (1000 / 33, "1000/33")]
)
def test_a_fractional_real_speed_rate_is_encoded_exactly(
    tmp_path: Path, fps: float, rate: str
) -> None:
    # Hopper's clips play a frame every 4th step of 0.008 s: 31.25 frames/s
    assert frame_rate(fps) == rate
    path = tmp_path / "clip.mp4"
    encode_mp4(_frames(47), path, fps=fps)
    info = probe(path)
    assert info.frames == 47
    assert info.fps == pytest.approx(fps, abs=0.01)
    with pytest.raises(ValueError, match="fps"):
        frame_rate(0.0)


def test_equal_frames_give_byte_identical_files(tmp_path: Path) -> None:
    encode_mp4(_frames(), tmp_path / "a.mp4")
    encode_mp4(_frames(), tmp_path / "b.mp4")
    assert (tmp_path / "a.mp4").read_bytes() == (tmp_path / "b.mp4").read_bytes()


def test_a_batch_encodes_each_clip_as_if_alone(tmp_path: Path) -> None:
    frames = _frames(20)
    paths = [tmp_path / f"{k}.mp4" for k in range(2)]
    with ClipEncoder(paths, 10, 48, 64) as encoder:
        for frame in frames:
            encoder.write(frame)
    for k, path in enumerate(paths):
        encode_mp4(frames[10 * k : 10 * k + 10], tmp_path / "alone.mp4")
        assert path.read_bytes() == (tmp_path / "alone.mp4").read_bytes()
        assert probe(path).frames == 10


def test_decoded_frames_match_the_input(tmp_path: Path) -> None:
    frames = _frames(8)
    encode_mp4(frames, tmp_path / "clip.mp4", VideoConfig(crf=0))
    decoded = read_frames(tmp_path / "clip.mp4")
    assert decoded.shape == frames.shape
    # yuv420p subsamples colour, so only close, not equal
    assert np.abs(decoded.astype(int) - frames).mean() < 4


def test_too_few_frames_is_an_error(tmp_path: Path) -> None:
    encoder = ClipEncoder([tmp_path / "a.mp4"], 10, 48, 64)
    encoder.write(_frames(1)[0])
    with pytest.raises(VideoEncodingError, match="1 of 10"):
        encoder.close()


@pytest.mark.parametrize(
    ("frames", "message"),
    [
        (np.zeros((3, 15, 16, 3), dtype=np.uint8), "even"),
        (np.zeros((3, 16, 16, 3), dtype=np.float32), "uint8"),
        (np.zeros((16, 16, 3), dtype=np.uint8), "L, H, W, 3"),
    ],
)
def test_bad_frames_are_rejected(tmp_path: Path, frames: np.ndarray, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        encode_mp4(frames, tmp_path / "x.mp4")


@pytest.mark.parametrize("kind", ["jpg", "png"])
def test_poster_is_an_image_of_the_frame(kind: str) -> None:
    frame = _frames(1)[0]
    data = poster_bytes(frame, VideoConfig(poster_format=kind))
    image = Image.open(io.BytesIO(data))
    assert image.format == {"jpg": "JPEG", "png": "PNG"}[kind]
    assert image.size == (48, 64)
