// C++ exceptions as Python exceptions: aperture::Error (bad parameters, bad file contents) is
// a ValueError with the command line's message; a FileError (file_errors.h) an OSError
// subclass chosen by errno, with the path as its filename.
#include <Python.h>

#include <cerrno>

#include "bindings.h"
#include "core/util/error.h"
#include "file_errors.h"

namespace aperture::python {

namespace {

PyObject* osErrorType(int errnum) {
  switch (errnum) {
    case ENOENT:
      return PyExc_FileNotFoundError;
    case EACCES:
    case EPERM:
      return PyExc_PermissionError;
    case EISDIR:
      return PyExc_IsADirectoryError;
    default:
      return PyExc_OSError;
  }
}

void translate(const std::exception_ptr& p, void*) {
  try {
    std::rethrow_exception(p);
  } catch (const FileError& e) {
    // OSError(errno, strerror, filename) sets .errno and .filename; the message is ours.
    nb::object error = nb::steal(PyObject_CallFunction(osErrorType(e.errnum()), "isz", e.errnum(),
                                                       e.what(), e.path().c_str()));
    if (!error.is_valid()) return;  // the call set its own exception
    PyErr_SetObject(reinterpret_cast<PyObject*>(Py_TYPE(error.ptr())), error.ptr());
  } catch (const Error& e) {
    PyErr_SetString(PyExc_ValueError, e.what());
  }
}

}  // namespace

void bindErrors(nb::module_&) { nb::register_exception_translator(translate); }

}  // namespace aperture::python
