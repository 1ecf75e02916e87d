// haptic::Recorder in Python: Client.record(path, ...) returns a Recorder, a context manager whose
// exit (or close()) drains, flushes and closes the file. close() and the destructor let go of the
// GIL (the writer thread is joined); the recorder's threads never run Python.

#include <pybind11/stl.h>

#include <memory>
#include <mutex>
#include <string>
#include <unordered_set>
#include <vector>

#include "bindings.hpp"
#include "binding_support.hpp"
#include "haptic/haptic.hpp"
#include "haptic/recorder.hpp"

namespace haptic::python {

namespace {

/// Every Recorder alive, closed at the interpreter's exit (atexit) so that its file is whole even
/// if the program never closed it.
class LiveRecorders {
 public:
  void add(Recorder* recorder) {
    std::lock_guard lock(mutex_);
    recorders_.insert(recorder);
  }
  void remove(Recorder* recorder) {
    std::lock_guard lock(mutex_);
    recorders_.erase(recorder);
  }
  void close_all() {
    std::vector<Recorder*> open;
    {
      std::lock_guard lock(mutex_);
      open.assign(recorders_.begin(), recorders_.end());
    }
    py::gil_scoped_release released;
    for (Recorder* recorder : open) recorder->close();
  }

 private:
  std::mutex mutex_;
  std::unordered_set<Recorder*> recorders_;
};

LiveRecorders& live_recorders() {
  static auto* recorders = new LiveRecorders;  // never destroyed: atexit may run after statics go
  return *recorders;
}

struct DeleteRecorder {
  void operator()(Recorder* recorder) const {
    live_recorders().remove(recorder);
    DeleteWithoutGil<Recorder>{}(recorder);
  }
};

using RecorderHolder = std::unique_ptr<Recorder, DeleteRecorder>;

RecorderOptions::Format format_from(const std::string& name) {
  if (name == "auto") return RecorderOptions::Format::kAuto;
  if (name == "csv") return RecorderOptions::Format::kCsv;
  if (name == "hdf5") return RecorderOptions::Format::kHdf5;
  throw InvalidArgumentError("record: format: '" + name + "' is none of 'auto', 'csv', 'hdf5'");
}

}  // namespace

void bind_recorder(py::module_& m) {
  StructBinder<RecorderStats>(m, "RecorderStats", "A recording's totals (Recorder.stats, close).")
      .readonly("samples_received", &RecorderStats::samples_received,
                "States the client accepted while recording")
      .readonly("samples_written", &RecorderStats::samples_written, "of those, the ones in the file")
      .readonly("dropped", &RecorderStats::dropped, "the ones that found the queue full")
      .readonly("events_written", &RecorderStats::events_written,
                "server events and connection changes in the file")
      .readonly("events_dropped", &RecorderStats::events_dropped,
                "the ones that found the event queue full")
      .readonly("write_errors", &RecorderStats::write_errors,
                "samples and events a failed write kept from the file")
      .readonly("first_error", &RecorderStats::first_error, "the first failure; empty if none")
      .finish();

  py::class_<Recorder, RecorderHolder> recorder(
      m, "Recorder",
      "Records what a Client receives into a CSV or HDF5 file (Client.record; docs/recorder.md). "
      "`with client.record(path) as recorder:` closes it at the end of the block.");
  recorder
      .def("stats", &Recorder::stats, "The totals so far: a RecorderStats.")
      .def("close", &Recorder::close, py::call_guard<py::gil_scoped_release>(),
           "Stops recording, writes what is queued, flushes and closes the file(s); the totals "
           "(a RecorderStats; again on later calls).")
      .def_property_readonly("recording", &Recorder::recording, "False once closed.")
      .def_property_readonly("path", &Recorder::path, "The samples' file.")
      .def_property_readonly("events_path", &Recorder::events_path,
                             "The events' file (path itself for HDF5); empty without events.")
      .def("__enter__", [](py::object self) { return self; })
      .def(
          "__exit__",
          [](Recorder& value, const py::args&) {
            py::gil_scoped_release released;
            value.close();
            return false;
          },
          "Closes the recorder.")
      .def("__repr__", [](const Recorder& r) {
        return py::str("Recorder(path={!r}, recording={})").format(r.path(), r.recording());
      });

  auto client_class = py::reinterpret_borrow<py::class_<Client>>(m.attr("Client"));
  client_class.def(
      "record",
      [](Client& client, const py::object& path, const std::string& format,
         std::size_t queue_capacity, bool events, bool overwrite) {
        // A str or any os.PathLike (pathlib.Path).
        RecorderOptions options{.path = py::str(py::module_::import("os").attr("fspath")(path)),
                                .format = format_from(format),
                                .queue_capacity = queue_capacity,
                                .events = events,
                                .overwrite = overwrite};
        Recorder* made = nullptr;
        {
          py::gil_scoped_release released;  // opens an event stream: an RPC
          made = new Recorder(client, options);
        }
        live_recorders().add(made);
        return RecorderHolder(made);
      },
      py::arg("path"), py::arg("format") = "auto", py::arg("queue_capacity") = 65536,
      py::arg("events") = true, py::arg("overwrite") = false,
      "Records every State this client accepts, and with `events` the server's events and the "
      "connection's changes, into `path`: CSV (.csv; events in <stem>.events.csv) or HDF5 (.h5, "
      ".hdf5), or as `format` ('csv', 'hdf5') says. A Recorder; raises "
      "hapticd.InvalidArgumentError naming the field for a bad path or option, or an existing "
      "file without overwrite.");

  py::module_::import("atexit").attr("register")(
      py::cpp_function([] { live_recorders().close_all(); }, py::name("_close_recorders_at_exit")));
}

}  // namespace haptic::python
