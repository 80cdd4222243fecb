// The extension module `aperture._aperture`; `aperture/__init__.py` re-exports it.
#include <nanobind/nanobind.h>

#include "bindings.h"

NB_MODULE(_aperture, m) {
  m.doc() = "aperture: Embree ray casting of meshes into depth, normals and ids (C++ core)";
  m.attr("__version__") = APERTURE_VERSION;
  aperture::python::bindErrors(m);
  aperture::python::bindCamera(m);
  aperture::python::bindScene(m);
  aperture::python::bindImageIo(m);
  aperture::python::bindAovTable(m);
  aperture::python::bindDistributed(m);
}
