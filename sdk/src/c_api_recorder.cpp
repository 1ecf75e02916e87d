// The C API (haptic/haptic_c.h): the recorder.
#include "c_api_internal.hpp"

using namespace haptic::c_api;  // this library's own helpers, for its C entry points

extern "C" {

// ---- the recorder ----

namespace {
void copy_recorder_stats(const haptic::RecorderStats& r, haptic_recorder_stats& c) {
  const std::uint32_t size = c.size;
  c = haptic_recorder_stats{};
  c.size = size;
  c.samples_received = r.samples_received;
  c.samples_written = r.samples_written;
  c.dropped = r.dropped;
  c.events_written = r.events_written;
  c.events_dropped = r.events_dropped;
  c.write_errors = r.write_errors;
  copy_text(c.first_error, sizeof(c.first_error), r.first_error);
}

haptic_recorder_options recorder_options_defaults() {
  haptic_recorder_options value{};
  haptic_recorder_options* options = &value;
  const haptic::RecorderOptions d;
  options->path = "";
  options->format = static_cast<int32_t>(d.format);
  options->events = d.events;
  options->overwrite = d.overwrite;
  options->queue_capacity = d.queue_capacity;
  return value;
}
}  // namespace
HAPTIC_C_INIT(haptic_recorder_options, recorder_options_defaults())

int haptic_client_record(haptic_client* client, const haptic_recorder_options* options,
                         haptic_recorder** out, haptic_error* err) {
  return guarded(err, [&] {
    require(out, "record", "out");
    *out = nullptr;
    require(client, "record", "client");
    const auto& c = sized<haptic_recorder_options>(options, "record", "options");
    haptic::RecorderOptions cpp;
    cpp.path = text_or_empty(c.path);
    cpp.format = converting("record", "options", [&] {
      return enum_from<haptic::RecorderOptions::Format>(c.format, HAPTIC_RECORDER_HDF5, "format");
    });
    cpp.events = c.events != 0;
    cpp.overwrite = c.overwrite != 0;
    cpp.queue_capacity = static_cast<std::size_t>(c.queue_capacity);
    *out = new haptic_recorder{haptic::Recorder(client->client, cpp)};
    return HAPTIC_OK;
  });
}

int haptic_recorder_get_stats(const haptic_recorder* recorder, haptic_recorder_stats* out,
                              haptic_error* err) {
  return guarded(err, [&] {
    require(recorder, "recorder_stats", "recorder");
    copy_recorder_stats(recorder->recorder.stats(), *SizedOut<haptic_recorder_stats>(out, "recorder_stats", "out"));
    return HAPTIC_OK;
  });
}

const char* haptic_recorder_path(const haptic_recorder* recorder) {
  return recorder != nullptr ? recorder->recorder.path().c_str() : "";
}

const char* haptic_recorder_events_path(const haptic_recorder* recorder) {
  return recorder != nullptr ? recorder->recorder.events_path().c_str() : "";
}

int haptic_recorder_close(haptic_recorder* recorder, haptic_recorder_stats* totals, haptic_error* err) {
  const int status = guarded(err, [&] {
    if (totals != nullptr) sized<haptic_recorder_stats>(totals, "recorder_close", "totals");
    return HAPTIC_OK;
  });
  if (recorder == nullptr) return status;
  const haptic::RecorderStats stats = recorder->recorder.close();  // never throws
  if (status == HAPTIC_OK && totals != nullptr) {
    copy_recorder_stats(stats, *SizedOut<haptic_recorder_stats>(totals, "recorder_close", "totals"));
  }
  delete recorder;
  return status;
}


}  // extern "C"
