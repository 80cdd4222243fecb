// What aperture.distributed needs of the core beyond rendering and writing: the one definition
// of a temporary file's name (core/io/atomic_file.h), so that a worker can find the
// temporaries a killed worker left beside the files it is about to write.
#include <nanobind/stl/optional.h>
#include <nanobind/stl/pair.h>
#include <nanobind/stl/string.h>

#include <optional>
#include <string>
#include <utility>

#include "bindings.h"
#include "core/io/atomic_file.h"

namespace aperture::python {

void bindDistributed(nb::module_& m) {
  m.def(
      "_parse_temporary_name",
      [](const std::string& fileName) -> std::optional<std::pair<std::string, long>> {
        const std::optional<TemporaryName> t = parseTemporaryName(fileName);
        if (!t) return std::nullopt;
        return std::make_pair(t->finalName, t->pid);
      },
      nb::arg("file_name"),
      "(NAME, PID) of a temporary file name '.NAME.tmp-PID-N...' made by an atomic write, "
      "None for any other name.");
}

}  // namespace aperture::python
