"""Errors carry the command line's messages: ValueError for bad parameters and contents,
OSError (FileNotFoundError) for files. Compared with the CLI's stderr for the same value."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import aperture
from conftest import cli_error


def after_source(message: str) -> str:
    """The part of a message after its source label ("--fov: " or "Camera(fov=...): ")."""
    return message.split(": ", 1)[1]


@pytest.mark.parametrize(
    "keywords,flags",
    [
        (dict(fov=300), ["--fov", "300"]),
        (dict(size=(0, 10)), ["--size", "0x10"]),
        (dict(type="persp"), ["--camera", "persp"]),
        (dict(type="orthographic", fov=40), ["--camera", "orthographic", "--fov", "40"]),
        (dict(fov=30, focal_length=50), ["--fov", "30", "--focal-length", "50"]),
    ],
)
def test_camera_errors_are_the_cli_messages(cli: Path, keywords: dict, flags: list[str]) -> None:
    expected = cli_error(cli, "render", "--quiet", "--eye", "0,0,5", *flags, "--out", "/tmp/unused.exr")
    with pytest.raises(ValueError) as raised:
        aperture.Camera(eye=(0, 0, 5), **keywords)
    message = str(raised.value)
    # The source names differ (--fov vs Camera(fov=...)); the rest is the same text.
    for flag, keyword in [("--camera", "Camera(type=...)"), ("--focal-length", "Camera(focal_length=...)"),
                          ("--fov", "Camera(fov=...)"), ("--size", "Camera(size=...)")]:
        expected = expected.replace(flag, keyword)
    assert message == expected


def test_aov_errors_are_the_cli_messages(cli: Path) -> None:
    expected = cli_error(cli, "render", "--quiet", "--aov", "depth,nromal", "--out", "/tmp/unused.exr")
    with pytest.raises(ValueError) as raised:
        aperture.Scene("procedural:cube").render(aperture.Camera(size=(8, 8)), aovs=["depth", "nromal"])
    assert str(raised.value) == expected
    assert "did you mean 'normal'" in expected


def test_normal_frame_error_names_the_value() -> None:
    # parseNormalFrame's message, as --normal-frame gives it.
    with pytest.raises(ValueError, match=r"unknown normal frame 'opencb' \(did you mean 'opencv'\?\)"):
        aperture.Scene("procedural:cube").render(aperture.Camera(size=(8, 8)), normal_frame="opencb")


def test_missing_files_are_file_not_found(cli: Path, tmp_path: Path) -> None:
    missing = tmp_path / "nope.ply"
    expected = cli_error(cli, "render", "--quiet", "--mesh", str(missing), "--out", str(tmp_path / "x.exr"))
    with pytest.raises(FileNotFoundError) as raised:
        aperture.Scene(missing)
    assert raised.value.strerror == expected
    assert raised.value.filename == str(missing)
    with pytest.raises(FileNotFoundError):
        aperture.load_cameras(tmp_path / "no_model")
    with pytest.raises(FileNotFoundError):
        aperture.read_exr(tmp_path / "none.exr")
    with pytest.raises(FileNotFoundError):
        aperture.write(tmp_path / "no_dir" / "d.npy", np.zeros((2, 2), np.float32))


def test_bad_file_contents_are_value_errors(tmp_path: Path) -> None:
    bad = tmp_path / "bad.ply"
    bad.write_text("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nend_header\n1\n")
    with pytest.raises(ValueError, match="bad.ply"):
        aperture.Scene(bad)


def test_keywords_are_checked_by_name() -> None:
    with pytest.raises(ValueError, match=r"unknown parameter 'fvo' \(did you mean 'fov'\?\)"):
        aperture.Camera(fvo=30)
    with pytest.raises(ValueError, match=r"unknown parameter 'apperture' \(did you mean 'aperture'\?\)"):
        aperture.Camera.look_at(eye=(0, 0, 5), at=(0, 0, 0), apperture=0.1)
    with pytest.raises(ValueError, match=r"Camera\(\): fov: expected a number, got a string"):
        aperture.Camera(fov="wide")
    with pytest.raises(TypeError):
        aperture.Scene().render(aperture.Camera(size=(4, 4)), aov="depth")  # type: ignore[call-arg]
    assert "fov" in aperture.camera_parameters()
    assert "fisheye" in aperture.camera_types()
