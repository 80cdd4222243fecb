"""render releases the GIL: a Python thread keeps counting while a large frame renders."""

from __future__ import annotations

import aperture

from conftest import count_during


def test_a_python_thread_runs_during_render() -> None:
    scene = aperture.Scene()
    camera = aperture.Camera(eye=(0, 4, 14), at=(0, 0, 0), size=(1600, 1200), spp=4)
    seconds, during = count_during(lambda: scene.render(camera, aovs="color,depth,normal"))
    assert seconds > 0.1, f"render too short ({seconds:.3f} s) to show anything"
    assert during > 10000, f"the counter advanced only {during} times in {seconds:.2f} s"
