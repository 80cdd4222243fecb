#pragma once
// The pieces of the extension module `aperture._aperture`, one binder per concern. Bindings
// only convert Python values and forward to the C++ libraries (the same road as the command
// line and job files); they never re-implement a check or a render.
#include <nanobind/nanobind.h>

#include <string>

#include "apps/services/render_options.h"
#include "cameras/schema/params.h"

namespace aperture::python {

namespace nb = nanobind;

/// Runs f() with the GIL released and TBB limited to `threads` (0: every core): how every long
/// call of a Scene (render, queries, scan) runs, so other Python threads go on meanwhile.
template <class F>
void withoutGil(int threads, const F& f) {
  nb::gil_scoped_release release;
  app::ThreadLimit limit(threads);
  f();
}

/// A Python `aperture.Camera`: resolved parameters (checked by the camera schema) and, for a
/// camera read from a file, the image's name.
struct PyCamera {
  CameraParams params;
  std::string name;
};

void bindErrors(nb::module_& m);       ///< aperture::Error -> ValueError, file errors -> OSError
void bindCamera(nb::module_& m);       ///< Camera, load_cameras
void bindScene(nb::module_& m);        ///< Scene, Scene.render
void bindImageIo(nb::module_& m);      ///< read_exr, write, read
void bindAovTable(nb::module_& m);     ///< _aov_table, _AovRegistration (for the tests)
void bindDistributed(nb::module_& m);  ///< _dead_temporaries, _dataset_extensions (distributed)

}  // namespace aperture::python
