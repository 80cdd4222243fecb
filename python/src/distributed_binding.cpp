// What aperture.distributed needs of the core beyond rendering and writing: the temporaries a
// killed worker left beside the files it is about to write (core/io/atomic_file.h, the one
// definition of a temporary file's name and of when its process is gone), and the dataset
// formats a Renderer writes (core/io/dataset_image.h).
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

#include <string>
#include <vector>

#include "bindings.h"
#include "core/io/atomic_file.h"
#include "core/io/dataset_image.h"

namespace aperture::python {

void bindDistributed(nb::module_& m) {
  m.def(
      "_dead_temporaries",
      [](const std::vector<std::string>& paths) {
        std::vector<std::string> dead;
        for (const TemporaryFile& t : findTemporaries(paths))
          if (!t.alive) dead.push_back(t.path);
        return dead;
      },
      nb::arg("paths"),
      "The temporaries ('.NAME.tmp-PID-N...') of the files `paths` whose process is gone on "
      "this host (a PID that cannot be a process counts as gone), sorted; as batch --resume "
      "finds them.");
  m.def(
      "_dataset_extensions", [] { return datasetExtensions(); },
      "The extensions (lower case, with the dot) of the dataset formats a Renderer writes.");
}

}  // namespace aperture::python
