#pragma once
// What the hapticd Python module's bindings share: Vec3 and Quaternion as NumPy arrays, a binder
// for the SDK's plain structs (keyword construction, repr, equality), (N, 3) arrays for lists of
// points, seconds for durations, and Python callables the SDK's own threads may call.

#include <Python.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <array>
#include <chrono>
#include <cmath>
#include <concepts>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "haptic/types.hpp"

namespace haptic::python {

namespace py = pybind11;

/// `values` as a new 1-D float64 array.
template <std::size_t N>
py::array_t<double> to_array(const std::array<double, N>& values) {
  py::array_t<double> array(static_cast<py::ssize_t>(N));
  for (std::size_t i = 0; i < N; ++i) array.mutable_at(static_cast<py::ssize_t>(i)) = values[i];
  return array;
}

/// Reads exactly N numbers from any sequence (list, tuple, NumPy array); false if `source` is not
/// one or holds anything but N real numbers (pybind11 then tries the next overload, or raises
/// TypeError naming the expected types).
template <std::size_t N>
bool read_numbers(py::handle source, std::array<double, N>& out) {
  if (!source || !PySequence_Check(source.ptr()) || PyUnicode_Check(source.ptr()) ||
      PyBytes_Check(source.ptr())) {
    return false;
  }
  const Py_ssize_t size = PySequence_Size(source.ptr());
  if (size != static_cast<Py_ssize_t>(N)) {
    PyErr_Clear();
    return false;
  }
  for (std::size_t i = 0; i < N; ++i) {
    py::object item = py::reinterpret_steal<py::object>(
        PySequence_GetItem(source.ptr(), static_cast<Py_ssize_t>(i)));
    if (!item || PyUnicode_Check(item.ptr())) {
      PyErr_Clear();
      return false;
    }
    const double value = PyFloat_AsDouble(item.ptr());
    if (value == -1.0 && PyErr_Occurred()) {
      PyErr_Clear();
      return false;
    }
    out[i] = value;
  }
  return true;
}

/// An (N, 3) float64 array of `points`.
py::array_t<double> points_to_array(const std::vector<Vec3>& points);
/// `array` (anything NumPy reads as an (N, 3) array of numbers; N may be 0) as points. Raises
/// ValueError naming `what` and the shape it got.
std::vector<Vec3> points_from_array(const py::handle& array, const char* what);
/// `array` (integers, any shape) as vertex indices, in order; ValueError naming `what` and the
/// first entry outside 0 … 2³² − 1.
std::vector<std::uint32_t> indices_from_array(const py::handle& array, const char* what);

/// Milliseconds as seconds (the Python API's unit for every duration).
inline double seconds(std::chrono::milliseconds duration) {
  return std::chrono::duration<double>(duration).count();
}
/// Seconds (a number) as milliseconds, rounded; ValueError naming `what` when negative or not
/// finite.
std::chrono::milliseconds milliseconds_from_seconds(double value, const char* what);
/// A steady_clock time as seconds on the same clock as Python's time.monotonic() (both read
/// CLOCK_MONOTONIC on Linux).
inline double monotonic_seconds(std::chrono::steady_clock::time_point time) {
  return std::chrono::duration<double>(time.time_since_epoch()).count();
}

/// Sets each keyword of `values` on `target`, an instance of a class StructBinder made, through
/// the attribute's own setter. TypeError for a name not in its `_fields` ("<unknown>: 'x'; its
/// fields: ...") or a value the field cannot take ("WallSpec.normal: cannot take (1, 2); expected
/// numpy.ndarray[3]").
void assign_fields(const py::object& target, const py::kwargs& values, const std::string& unknown);

/// Binds one of the SDK's plain structs: each field as an attribute, a constructor taking any of
/// them by keyword (TypeError naming an unknown one), a repr listing them, and == where the
/// struct has one.
///
///   StructBinder<WallSpec>(m, "WallSpec", "A half-space wall ...")
///       .field("point", &WallSpec::point, "...")
///       .finish();
template <class T>
class StructBinder {
 public:
  StructBinder(py::handle scope, const char* name, const char* doc)
      : class_(scope, name, doc), name_(name) {}

  /// A field read and written as the member is (Vec3 as a NumPy array: assign whole values,
  /// `spec.point[0] = 1` changes a copy).
  template <class Member>
  StructBinder& field(const char* name, Member T::*member, const char* doc) {
    class_.def_readwrite(name, member, doc);
    names_.emplace_back(name);
    return *this;
  }
  /// A field read and written through functions (units or shapes the member does not have).
  template <class Getter, class Setter>
  StructBinder& property(const char* name, Getter getter, Setter setter, const char* doc) {
    class_.def_property(name, getter, setter, doc);
    names_.emplace_back(name);
    return *this;
  }
  /// Read-only attributes (results the server gives).
  template <class Member>
  StructBinder& readonly(const char* name, Member T::*member, const char* doc) {
    class_.def_readonly(name, member, doc);
    names_.emplace_back(name);
    return *this;
  }
  template <class Getter>
  StructBinder& readonly_property(const char* name, Getter getter, const char* doc) {
    class_.def_property_readonly(name, getter, doc);
    names_.emplace_back(name);
    return *this;
  }
  py::class_<T>& cls() { return class_; }

  /// Adds the keyword constructor, repr and equality; call once, after the fields.
  py::class_<T>& finish() {
    class_.attr("_fields") = py::tuple(py::cast(names_));
    const std::string type_name = name_;
    class_.def(py::init([type_name](const py::kwargs& values) {
                 T value{};
                 // A borrowed Python view of `value`, so that each keyword goes through the same
                 // attribute setter (and conversion) as a later assignment would.
                 assign_fields(py::cast(&value, py::return_value_policy::reference), values,
                               type_name + "() has no field");
                 return value;
               }),
               ("Any of the fields by keyword: " + join(names_) + ".").c_str());
    class_.def("__repr__", [type_name](const py::object& self) {
      std::string text = type_name + "(";
      for (const py::handle field : py::tuple(py::type::of(self).attr("_fields"))) {
        if (text.back() != '(') text += ", ";
        text += field.cast<std::string>() + "=" + py::repr(self.attr(field)).template cast<std::string>();
      }
      return text + ")";
    });
    if constexpr (std::equality_comparable<T>) {
      class_.def(
          "__eq__", [](const T& a, const T& b) { return a == b; }, py::is_operator());
      class_.attr("__hash__") = py::none();  // mutable: not hashable
    }
    class_.def("__copy__", [](const T& self) { return T(self); });
    class_.def("__deepcopy__", [](const T& self, const py::dict&) { return T(self); });
    return class_;
  }

 private:
  static std::string join(const std::vector<std::string>& names) {
    std::string text;
    for (const std::string& name : names) text += (text.empty() ? "" : ", ") + name;
    return text;
  }

  py::class_<T> class_;
  std::string name_;
  std::vector<std::string> names_;  // the fields, in order: the class's _fields
};

/// A Python callable that the SDK's threads may hold, copy, call and drop without holding the
/// GIL: each call takes the GIL, and an exception the callable raises goes to
/// sys.unraisablehook (named by `where`) instead of into the SDK's thread.
class PythonCallback {
 public:
  PythonCallback(py::object callable, const char* where)
      : held_(new py::object(std::move(callable)),
              [](py::object* object) {
                if (!Py_IsInitialized()) return;  // the interpreter is gone: leak it
                py::gil_scoped_acquire gil;
                delete object;
              }),
        where_(where) {}

  template <class Argument>
  void operator()(const Argument& argument) const {
    // A thread taking the GIL while the interpreter shuts down would never return.
    if (!Py_IsInitialized() || _Py_IsFinalizing()) return;
    py::gil_scoped_acquire gil;
    try {
      (*held_)(argument);
    } catch (py::error_already_set& error) {
      error.discard_as_unraisable(where_);
    } catch (const std::exception& error) {
      // A C++ exception from converting the argument: report it the same way.
      PyErr_SetString(PyExc_RuntimeError, error.what());
      PyErr_WriteUnraisable(py::str(where_).ptr());
    }
  }

 private:
  std::shared_ptr<py::object> held_;
  const char* where_;
};

/// `callable` as the std::function the SDK takes; None gives an empty one (which stops the
/// callbacks). TypeError if it is neither None nor callable.
template <class Argument>
std::function<void(const Argument&)> sdk_callback(const py::object& callable, const char* where) {
  if (callable.is_none()) return {};
  if (!PyCallable_Check(callable.ptr())) {
    throw py::type_error(std::string(where) + ": expected a callable or None, got " +
                         py::repr(callable).cast<std::string>());
  }
  PythonCallback call(callable, where);
  return [call](const Argument& argument) { call(argument); };
}

/// Deletes without the GIL: a Client's or handle's destructor makes calls to the server and
/// waits for the SDK's threads, whose Python callbacks need the GIL to finish.
template <class T>
struct DeleteWithoutGil {
  void operator()(T* value) const {
    if (value == nullptr) return;
    if (Py_IsInitialized() && PyGILState_Check()) {
      py::gil_scoped_release released;
      delete value;
    } else {
      delete value;
    }
  }
};

}  // namespace haptic::python

namespace pybind11::detail {

/// A value of N doubles ⇄ a float64 array of N (from any sequence of N numbers); `Fields` lists
/// its members in the array's order.
template <class Value, auto... Fields>
struct fixed_array_caster {
  static constexpr std::size_t kSize = sizeof...(Fields);
  Value value;
  bool load(handle source, bool /*convert*/) {
    std::array<double, kSize> numbers{};
    if (!haptic::python::read_numbers(source, numbers)) return false;
    std::size_t i = 0;
    ((value.*Fields = numbers[i++]), ...);
    return true;
  }
  static handle cast(const Value& v, return_value_policy, handle) {
    return haptic::python::to_array(std::array<double, kSize>{(v.*Fields)...}).release();
  }
  operator Value*() { return &value; }
  operator Value&() { return value; }
  template <typename T>
  using cast_op_type = pybind11::detail::cast_op_type<T>;
};

/// haptic::Vec3 ⇄ a float64 array of 3.
template <>
struct type_caster<haptic::Vec3>
    : fixed_array_caster<haptic::Vec3, &haptic::Vec3::x, &haptic::Vec3::y, &haptic::Vec3::z> {
  static constexpr auto name = const_name("numpy.ndarray[3]");
};

/// haptic::Quaternion ⇄ a float64 array (w, x, y, z).
template <>
struct type_caster<haptic::Quaternion>
    : fixed_array_caster<haptic::Quaternion, &haptic::Quaternion::w, &haptic::Quaternion::x,
                         &haptic::Quaternion::y, &haptic::Quaternion::z> {
  static constexpr auto name = const_name("numpy.ndarray[4] (w, x, y, z)");
};

}  // namespace pybind11::detail
