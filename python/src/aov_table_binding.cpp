// The AOV table (core/aov/aov_table.h) seen from Python, for the tests: _aov_table() lists the rows
// as the arrays of render and read_exr give them; _AovRegistration adds a row for as long as it
// is open, as a test-only AOV that the arrays must pick up with no code of their own.
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

#include <memory>
#include <optional>

#include "bindings.h"
#include "core/aov/aov_table.h"
#include "core/util/error.h"

namespace aperture::python {

namespace {

/// A row as a dict: name, exr_channels, dtype ("float32", "uint32"), channels, miss, in_all.
nb::dict rowDict(const AovRow& row) {
  nb::dict d;
  d["name"] = row.name;
  d["exr_channels"] = row.exrChannels;
  d["dtype"] = row.isFloat() ? "float32" : "uint32";
  d["channels"] = row.channels();
  d["miss"] = row.miss;
  d["in_all"] = row.inAll;
  return d;
}

/// An open registration of a test-only row; close() (or the end of a `with`) removes it.
struct PyAovRegistration {
  std::optional<AovRegistration> registration;
  void close() { registration.reset(); }
};

}  // namespace

void bindAovTable(nb::module_& m) {
  m.def(
      "_aov_table",
      [] {
        nb::list rows;
        for (const AovRow& row : aovTable()) rows.append(rowDict(row));
        return rows;
      },
      "The AOV table's rows (core/aov/aov_table.h), in table order.");
  nb::class_<PyAovRegistration>(m, "_AovRegistration")
      .def(
          "__init__",
          [](PyAovRegistration* self, const std::string& name,
             const std::vector<std::string>& exrChannels, const std::string& dtype, double miss) {
            if (dtype != "float32" && dtype != "uint32")
              throw Error(cat("dtype '", dtype, "': float32 or uint32"));
            AovRow row;
            row.name = name;
            row.inAll = false;
            row.type = dtype == "float32" ? AovType::Float32 : AovType::UInt32;
            row.exrChannels = exrChannels;
            row.miss = miss;
            new (self) PyAovRegistration();
            self->registration.emplace(std::move(row));
          },
          nb::arg("name"), nb::arg("exr_channels"), nb::arg("dtype"), nb::arg("miss"))
      .def("close", &PyAovRegistration::close)
      .def("__enter__", [](nb::object self) { return self; })
      .def("__exit__", [](PyAovRegistration& self, nb::args) { self.close(); });
}

}  // namespace aperture::python
