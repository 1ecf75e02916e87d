// hapticd._native: the C++ SDK (haptic::sdk) for Python. The package `hapticd` (python/hapticd)
// re-exports it; docs/python.md describes the API.

#include <pybind11/pybind11.h>

#include <string>

#include "bindings.hpp"
#include "haptic/haptic.hpp"

namespace haptic::python {

namespace py = pybind11;

namespace {

struct ErrorClass {
  ErrorCode code;
  const char* name;
  const char* doc;
};

// One Python class per C++ exception, all under hapticd.Error (itself a RuntimeError).
constexpr ErrorClass kErrorClasses[] = {
    {ErrorCode::kConnection, "ConnectionError", "The server is unreachable or too slow."},
    {ErrorCode::kInvalidArgument, "InvalidArgumentError", "A field was wrong; the message names it."},
    {ErrorCode::kNotFound, "NotFoundError", "No such session or item."},
    {ErrorCode::kPermissionDenied, "PermissionDeniedError",
     "The item belongs to another client, or the token's role forbids the call."},
    {ErrorCode::kResourceExhausted, "ResourceExhaustedError", "A server limit was reached."},
    {ErrorCode::kFailedPrecondition, "FailedPreconditionError",
     "Not possible in the server's state (e.g. step() in real time)."},
    {ErrorCode::kVersionMismatch, "VersionMismatchError",
     "Client and server speak different API versions (client_version, server_version)."},
    {ErrorCode::kInternal, "InternalError", "Anything else."},
    {ErrorCode::kUnauthenticated, "UnauthenticatedError",
     "No token, or one the server does not know or that has expired."},
};

/// Raises `error` as the module's class for its code, with attribute `code` (and the versions of
/// a VersionMismatchError).
void raise(const Error& error) {
  const py::module_ module = py::module_::import("hapticd._native");
  const char* name = "Error";
  for (const ErrorClass& entry : kErrorClasses) {
    if (entry.code == error.code()) name = entry.name;
  }
  const py::object type = module.attr(name);
  py::object instance = type(error.what());
  instance.attr("code") = py::cast(error.code());
  if (const auto* mismatch = dynamic_cast<const VersionMismatchError*>(&error)) {
    instance.attr("client_version") = mismatch->client_version();
    instance.attr("server_version") = mismatch->server_version();
  }
  PyErr_SetObject(type.ptr(), instance.ptr());
}

}  // namespace

void bind_errors(py::module_& m) {
  py::enum_<ErrorCode>(m, "ErrorCode", "What kind of failure a hapticd.Error is.")
      .value("CONNECTION", ErrorCode::kConnection)
      .value("INVALID_ARGUMENT", ErrorCode::kInvalidArgument)
      .value("NOT_FOUND", ErrorCode::kNotFound)
      .value("PERMISSION_DENIED", ErrorCode::kPermissionDenied)
      .value("RESOURCE_EXHAUSTED", ErrorCode::kResourceExhausted)
      .value("FAILED_PRECONDITION", ErrorCode::kFailedPrecondition)
      .value("VERSION_MISMATCH", ErrorCode::kVersionMismatch)
      .value("INTERNAL", ErrorCode::kInternal)
      .value("UNAUTHENTICATED", ErrorCode::kUnauthenticated);

  const auto make_class = [&m](const char* name, PyObject* base, const char* doc) {
    const std::string qualified = std::string("hapticd.") + name;
    py::object type = py::reinterpret_steal<py::object>(
        PyErr_NewExceptionWithDoc(qualified.c_str(), doc, base, nullptr));
    if (!type) throw py::error_already_set();
    m.attr(name) = type;
    return type;
  };
  const py::object base = make_class(
      "Error", PyExc_RuntimeError,
      "A failure the server or the SDK reports. str(error) reads '<call>: <field path>: <what is "
      "wrong>'; error.code is its ErrorCode.");
  for (const ErrorClass& entry : kErrorClasses) make_class(entry.name, base.ptr(), entry.doc);

  py::register_exception_translator([](std::exception_ptr thrown) {
    try {
      if (thrown) std::rethrow_exception(thrown);
    } catch (const Error& error) {
      raise(error);
    }
  });
}

}  // namespace haptic::python

PYBIND11_MODULE(_native, m) {
  m.doc() = "hapticd's C++ client SDK (haptic::sdk); use it through the package `hapticd`.";
  haptic::python::bind_errors(m);
  haptic::python::bind_value_types(m);
  haptic::python::bind_client(m);
  haptic::python::bind_recorder(m);
}
