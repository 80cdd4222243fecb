"""render releases the GIL: a Python thread keeps counting while a large frame renders."""

from __future__ import annotations

import threading
import time

import aperture


def test_a_python_thread_runs_during_render() -> None:
    scene = aperture.Scene()
    camera = aperture.Camera(eye=(0, 4, 14), at=(0, 0, 0), size=(1600, 1200), spp=4)
    count = 0
    stop = threading.Event()

    def counter() -> None:
        nonlocal count
        while not stop.is_set():
            count += 1

    thread = threading.Thread(target=counter)
    thread.start()
    time.sleep(0.05)  # the thread is running
    before = count
    start = time.perf_counter()
    scene.render(camera, aovs="color,depth,normal")
    seconds = time.perf_counter() - start
    during = count - before
    stop.set()
    thread.join()
    assert seconds > 0.1, f"render too short ({seconds:.3f} s) to show anything"
    # With the GIL held for the whole render the counter could only have advanced in the
    # few switch intervals before the call took it; released, it counts millions a second.
    assert during > 10000, f"the counter advanced only {during} times in {seconds:.2f} s"
