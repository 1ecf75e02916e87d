#include "recording/replay.hpp"

#include <grpcpp/grpcpp.h>

#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cstdio>
#include <map>
#include <utility>
#include <vector>

#include "haptic/io/session_secret.hpp"
#include "haptic/v1/recording.pb.h"
#include "haptic/v1/service.grpc.pb.h"
#include "recording/recording_file.hpp"

namespace haptic::recording {
namespace {

using Stub = v1::Haptic::Stub;

/// The recorded configuration, made to replay: lockstep, loopback, ephemeral ports, no metrics,
/// leases that never lapse (replay sessions send no heartbeats) and room for every session.
v1::ServerConfig replay_config(const v1::RecordHeader& header) {
  v1::ServerConfig config = header.config();
  config.set_time_mode(v1::LOCKSTEP);
  config.set_grpc_address("127.0.0.1:0");
  config.set_udp_address("127.0.0.1");
  config.set_udp_port(0);
  config.clear_metrics_address();
  config.set_status_period_s(0);
  config.set_insecure_remote_access(false);
  config.clear_security();
  config.set_lease_timeout_ms(24u * 3600u * 1000u);
  const std::uint32_t sessions = std::max<std::uint32_t>(config.max_sessions(), 32) + 1;
  config.set_max_sessions(sessions);
  config.set_max_sessions_per_peer(sessions);
  config.set_session_open_rate_per_peer(1000.0);
  config.set_session_open_burst_per_peer(sessions);
  return config;
}

struct ReplaySession {
  std::uint64_t id = 0;
  std::string secret;
};

/// What a recorded sample says, kept until the replay has run its tick (plain values: a few
/// thousand are held at a time, none allocates).
struct RecordedValues {
  std::uint64_t tick = 0;
  std::uint32_t port = 0;
  engine::Vec3 force;
  engine::Vec3 position;

  explicit RecordedValues(const v1::RecordedSample& sample)
      : tick(sample.tick()),
        port(sample.port()),
        force{sample.force().x(), sample.force().y(), sample.force().z()},
        position{sample.position().x(), sample.position().y(), sample.position().z()} {}
};

std::string vec_text(const engine::Vec3& v) {
  char text[160];
  std::snprintf(text, sizeof text, "(%.17g, %.17g, %.17g)", v.x, v.y, v.z);
  return text;
}

bool same_bits(const engine::Vec3& recorded, const engine::Vec3& replayed) {
  return std::bit_cast<std::uint64_t>(recorded.x) == std::bit_cast<std::uint64_t>(replayed.x) &&
         std::bit_cast<std::uint64_t>(recorded.y) == std::bit_cast<std::uint64_t>(replayed.y) &&
         std::bit_cast<std::uint64_t>(recorded.z) == std::bit_cast<std::uint64_t>(replayed.z);
}

class Replay {
 public:
  Replay(const v1::RecordHeader& header, const ReplayServers& servers)
      : server_(servers.start(replay_config(header))) {
    stub_ = v1::Haptic::NewStub(grpc::CreateChannel("127.0.0.1:" + std::to_string(server_->grpc_port()),
                                                    grpc::InsecureChannelCredentials()));
    // A session of the replay's own steps the loop (stepping is no recorded client's change).
    stepper_ = open("hapticd-replay", 0);
  }
  ~Replay() {
    if (!shut_down_) server_->shutdown();
  }

  /// The recorded server's shutdown: the same ramp to zero, its ticks kept for comparison.
  void shut_down() {
    server_->shutdown();
    shut_down_ = true;
    for (std::uint64_t t = completed_ + 1;; ++t) {
      bool any = false;
      for (std::size_t port = 0; port < server_->device_ports(); ++port) {
        runtime::TickSample sample;
        if (server_->samples(port).read(t, sample)) {
          replayed_[{t, port}] = sample;
          any = true;
        }
      }
      if (!any) break;
      completed_ = t;
    }
    report_.ticks = completed_;
  }

  /// Runs ticks until `tick` is completed, keeping each tick's samples until compared.
  void advance_to(std::uint64_t tick) {
    constexpr std::uint64_t kPiece = runtime::SampleRing::kCapacity / 2;
    if (shut_down_) return;  // no more ticks: what was recorded past the ramp is not replayed
    while (completed_ < tick) {
      v1::StepRequest request;
      request.set_session_id(stepper_.id);
      request.set_ticks(static_cast<std::uint32_t>(std::min(tick - completed_, kPiece)));
      v1::StepResponse reply;
      call("Step", &Stub::Step, stepper_, request, reply);
      for (std::uint64_t t = completed_ + 1; t <= reply.tick(); ++t) {
        for (std::size_t port = 0; port < server_->device_ports(); ++port) {
          runtime::TickSample sample;
          if (server_->samples(port).read(t, sample)) replayed_[{t, port}] = sample;
        }
      }
      completed_ = reply.tick();
      report_.ticks = completed_;
      if (progress_ && completed_ / 10000 != (completed_ - request.ticks()) / 10000) progress_(completed_);
    }
  }

  void compare(const RecordedValues& recorded) {
    advance_to(recorded.tick);
    const auto found = replayed_.find({recorded.tick, recorded.port});
    if (found == replayed_.end() && shut_down_) {
      ++report_.samples_not_replayed;  // the recorded ramp ran longer than the replay's
      return;
    }
    if (found == replayed_.end()) {
      throw ReplayError("tick " + std::to_string(recorded.tick) + " port " +
                        std::to_string(recorded.port) + ": the replay has no such sample (is the "
                        "recording's configuration another device?)");
    }
    const runtime::TickSample& replayed = found->second;
    ++report_.samples_compared;
    const bool force_same = same_bits(recorded.force, replayed.F_T_W);
    const bool position_same = same_bits(recorded.position, replayed.p_WT);
    if (!force_same || !position_same) {
      if (report_.samples_differing == 0) {
        const char* what = force_same ? "position" : "force";
        report_.first_difference =
            "tick " + std::to_string(recorded.tick) + " port " + std::to_string(recorded.port) +
            ": " + what + " recorded " +
            vec_text(force_same ? recorded.position : recorded.force) + ", replayed " +
            vec_text(force_same ? replayed.p_WT : replayed.F_T_W);
      }
      ++report_.samples_differing;
    }
    // What is compared is done with; anything older than a ring behind never will be.
    replayed_.erase(found);
    while (!replayed_.empty() &&
           replayed_.begin()->first.first + runtime::SampleRing::kCapacity < recorded.tick) {
      replayed_.erase(replayed_.begin());
    }
  }

  void apply(const v1::RecordedChange& change) {
    advance_to(change.after_tick());
    ++report_.changes;
    if (change.has_shutdown()) {
      shut_down();
      return;
    }
    const std::string at = "the change after tick " + std::to_string(change.after_tick()) +
                           " of session " + std::to_string(change.session_id());
    if (change.has_opened()) {
      sessions_[change.session_id()] = open(change.opened().client_name(), change.opened().device_index());
      return;
    }
    const auto session = sessions_.find(change.session_id());
    if (session == sessions_.end()) throw ReplayError(at + ": the recording never opened that session");
    const ReplaySession& as = session->second;
    v1::ItemRef item;
    v1::Empty empty;
    const auto expect_id = [&](std::uint64_t recorded, std::uint64_t replayed) {
      if (recorded != replayed) {
        throw ReplayError(at + ": the item was numbered " + std::to_string(recorded) +
                          " when recorded and " + std::to_string(replayed) + " now");
      }
    };
    switch (change.change_case()) {
      case v1::RecordedChange::kEnded: {
        v1::SessionRef request;
        request.set_session_id(as.id);
        call("CloseSession", &Stub::CloseSession, as, request, empty);
        sessions_.erase(session);
        break;
      }
      case v1::RecordedChange::kObjectCreated: {
        v1::CreateObjectRequest request;
        request.set_session_id(as.id);
        *request.mutable_object() = change.object_created().object();
        call("CreateObject", &Stub::CreateObject, as, request, item);
        expect_id(change.object_created().id(), item.id());
        break;
      }
      case v1::RecordedChange::kObjectUpdated: {
        v1::UpdateObjectRequest request;
        request.set_session_id(as.id);
        request.set_object_id(change.object_updated().id());
        *request.mutable_object() = change.object_updated().object();
        call("UpdateObject", &Stub::UpdateObject, as, request, item);
        break;
      }
      case v1::RecordedChange::kObjectDeleted:
      case v1::RecordedChange::kFieldDeleted: {
        const bool object = change.has_object_deleted();
        v1::DeleteRequest request;
        request.set_session_id(as.id);
        request.set_id(object ? change.object_deleted().id() : change.field_deleted().id());
        if (object) {
          call("DeleteObject", &Stub::DeleteObject, as, request, empty);
        } else {
          call("DeleteField", &Stub::DeleteField, as, request, empty);
        }
        break;
      }
      case v1::RecordedChange::kFieldCreated: {
        v1::CreateFieldRequest request;
        request.set_session_id(as.id);
        *request.mutable_field() = change.field_created().field();
        call("CreateField", &Stub::CreateField, as, request, item);
        expect_id(change.field_created().id(), item.id());
        break;
      }
      case v1::RecordedChange::kFieldUpdated: {
        v1::UpdateFieldRequest request;
        request.set_session_id(as.id);
        request.set_field_id(change.field_updated().id());
        *request.mutable_field() = change.field_updated().field();
        call("UpdateField", &Stub::UpdateField, as, request, empty);
        break;
      }
      case v1::RecordedChange::kSceneApplied: {
        v1::ApplySceneRequest request;
        request.set_session_id(as.id);
        *request.mutable_scene() = change.scene_applied().scene();
        v1::ApplySceneResponse reply;
        call("ApplyScene", &Stub::ApplyScene, as, request, reply);
        break;
      }
      case v1::RecordedChange::kOperatorInput: {
        v1::SetOperatorRequest request;
        request.set_session_id(as.id);
        *request.mutable_input() = change.operator_input();
        call("SetOperator", &Stub::SetOperator, as, request, empty);
        break;
      }
      default:
        throw ReplayError(at + ": a change this hapticd does not know (a newer recording?)");
    }
  }

  ReplayReport& report() { return report_; }
  void on_progress(std::function<void(std::uint64_t)> progress) { progress_ = std::move(progress); }

 private:
  ReplaySession open(const std::string& client_name, std::uint32_t device_index) {
    v1::OpenSessionRequest request;
    request.set_client_name(client_name);
    request.set_device_index(device_index);
    request.set_api_version(v1::API_VERSION_CURRENT);
    v1::OpenSessionResponse reply;
    call("OpenSession", &Stub::OpenSession, ReplaySession{}, request, reply);
    return {reply.session_id(), reply.session_secret()};
  }

  template <typename Request, typename Reply>
  void call(const char* name,
            grpc::Status (Stub::*method)(grpc::ClientContext*, const Request&, Reply*),
            const ReplaySession& as, const Request& request, Reply& reply) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
    if (!as.secret.empty()) context.AddMetadata(io::kSessionSecretMetadataKey, as.secret);
    const grpc::Status status = (stub_.get()->*method)(&context, request, &reply);
    if (!status.ok()) {
      throw ReplayError(std::string(name) + " after tick " + std::to_string(completed_) +
                        " was refused this time: " + status.error_message());
    }
  }

  std::unique_ptr<ReplayServer> server_;
  std::unique_ptr<Stub> stub_;
  ReplaySession stepper_;
  std::map<std::uint64_t, ReplaySession> sessions_;  // recorded id -> replay session
  std::map<std::pair<std::uint64_t, std::size_t>, runtime::TickSample> replayed_;
  std::uint64_t completed_ = 0;
  bool shut_down_ = false;
  ReplayReport report_;
  std::function<void(std::uint64_t)> progress_;
};

}  // namespace

ReplayReport replay_recording(const std::string& path, const ReplayServers& servers,
                              const std::function<void(std::uint64_t ticks)>& progress) {
  std::unique_ptr<RecordingReader> reader;
  try {
    reader = std::make_unique<RecordingReader>(path);
  } catch (const std::exception& error) {
    throw ReplayError(error.what());
  }
  v1::Record record;
  const bool read = reader->next(record);
  if (!read && !reader->error().empty() && reader->records() == 0 && reader->file_bytes() > 0 &&
      reader->error().find("checksum") != std::string::npos) {
    // The reader decompresses ahead: a small file's wrong checksum shows before its first record.
    throw ReplayError("'" + path + "' is damaged: " + reader->error());
  }
  if (!read || !record.has_header() || record.header().format() != "hapticd-recording") {
    throw ReplayError("'" + path + "' is not a hapticd recording" +
                      (reader->error().empty() ? std::string() : " (" + reader->error() + ")"));
  }
  const v1::RecordHeader header = record.header();
  if (header.version() != 1) {
    throw ReplayError("'" + path + "' is a recording of version " + std::to_string(header.version()) +
                      "; this hapticd reads version 1");
  }
  if (header.start_tick() != 0) {
    throw ReplayError("'" + path + "' begins at tick " + std::to_string(header.start_tick() + 1) +
                      " of its run: the device's state then is not in it, so the run cannot be "
                      "replayed (record from the start: hapticd --record, or StartRecording "
                      "before the first Step or after a Reset)");
  }
  if (const std::string error = servers.validate(replay_config(header)); !error.empty()) {
    throw ReplayError("'" + path + "': its configuration does not validate here: " + error);
  }
  Replay replay(header, servers);
  replay.on_progress(progress);
  replay.report().real_time = header.config().time_mode() != v1::LOCKSTEP;
  // Samples are held until a change, the end or kAhead of them: the replay then runs their ticks
  // in Steps of up to half a ring, not one Step a tick.
  constexpr std::size_t kAhead = 4096;
  std::vector<RecordedValues> ahead;
  ahead.reserve(kAhead);
  std::uint64_t ahead_through = 0;  // the last tick among them
  const auto compare_ahead = [&] {
    if (ahead.empty()) return;
    replay.advance_to(ahead_through);
    for (const RecordedValues& recorded : ahead) replay.compare(recorded);
    ahead.clear();
  };
  // The last whole record, for a recording cut short: a sample (its tick and port), a change (the
  // tick it followed) or the header.
  enum class Last { kHeader, kSample, kChange } last = Last::kHeader;
  std::uint64_t last_tick = 0;
  std::uint32_t last_port = 0;
  bool ended = false;
  while (reader->next(record)) {
    if (record.has_sample()) {
      ahead.emplace_back(record.sample());
      ahead_through = std::max(ahead_through, record.sample().tick());
      if (ahead.size() == kAhead) compare_ahead();
      last = Last::kSample;
      last_tick = record.sample().tick();
      last_port = record.sample().port();
    } else if (record.has_change()) {
      compare_ahead();
      replay.apply(record.change());
      last = Last::kChange;
      last_tick = record.change().after_tick();
    } else if (record.has_end()) {
      compare_ahead();
      replay.report().samples_missed = record.end().samples_missed();
      replay.report().stopped_because = record.end().stopped_because();
      ended = true;
      break;
    }
  }
  compare_ahead();
  if (ended) {
    // The end record is not the end of the file: after it comes the compressed stream's end and
    // its checksum, which is what says the records read are the ones written. A file without it
    // (its last bytes lost) or with a wrong one is not a whole recording.
    v1::Record after;
    const bool more = reader->next(after);
    const std::string where = "ends after its end record (record " + std::to_string(reader->records()) +
                              ", " + std::to_string(reader->file_bytes()) + " bytes of file)";
    if (more) throw ReplayError("'" + path + "' is damaged: it holds records after its end record");
    if (!reader->error().empty() && !reader->cut_short()) {
      throw ReplayError("'" + path + "' is damaged: it " + where + ", but " + reader->error());
    }
    if (reader->cut_short()) {
      replay.report().stopped_because = "was cut short";
      throw ReplayCutShort("'" + path + "' is cut short: it " + where +
                               " but before its compressed stream's end and checksum, so what it "
                               "holds cannot be verified (zstd -t calls it premature); replayed as "
                               "far as it goes",
                           replay.report());
    }
    return replay.report();
  }
  // No end record. What was written is replayed all the same; but a whole run it is not.
  const std::string last_record =
      last == Last::kSample   ? "the sample of tick " + std::to_string(last_tick) + " port " +
                                    std::to_string(last_port)
      : last == Last::kChange ? "a change after tick " + std::to_string(last_tick)
                              : std::string("the header");
  const std::string where =
      "stops after record " + std::to_string(reader->records()) + " (" + last_record +
      "), at byte " + std::to_string(reader->offset()) + " of its records (" +
      std::to_string(reader->file_bytes()) + " bytes of file)";
  if (!reader->cut_short() && !reader->error().empty()) {
    throw ReplayError("'" + path + "' is damaged: it " + where + ": " + reader->error());
  }
  replay.report().stopped_because = "was cut short";
  throw ReplayCutShort(
      "'" + path + "' is cut short: it " + where + ": " +
          (reader->error().empty() ? "the file ends without the recording's end record"
                                   : reader->error()) +
          "; replayed as far as it goes",
      replay.report());
}

const char* const kReplayHelp =
    "replay a recording in lockstep and compare every tick's force with it, bit for bit; exit 0 "
    "when all are the same, 1 when any differs, 2 when it cannot be replayed, 3 when it is cut "
    "short (no end record: its recorder was killed, or its disk filled) and what it holds is the "
    "same up to its last whole record";

int replay_command(const std::string& path, const ReplayServers& servers, std::FILE* out,
                   std::FILE* err) {
  // Progress on a terminal only: a log or a pipe gets the result alone.
  const bool terminal = ::isatty(::fileno(err)) != 0;
  const auto progress = [terminal, err](std::uint64_t ticks) {
    if (terminal) std::fprintf(err, "\rreplay: %llu ticks", static_cast<unsigned long long>(ticks));
  };
  ReplayReport report;
  std::string cut_short;
  try {
    report = replay_recording(path, servers, progress);
  } catch (const ReplayCutShort& cut) {
    report = cut.report;
    cut_short = cut.what();
  } catch (const ReplayError& error) {
    if (terminal) std::fprintf(err, "\r\x1b[K");
    std::fprintf(err, "hapticd --replay: %s\n", error.what());
    return kReplayRefused;
  }
  if (terminal) std::fprintf(err, "\r\x1b[K");
  std::fprintf(out,
               "replay of %s: %llu ticks, %llu changes, %llu samples compared, %llu differ; the "
               "recording %s, %llu samples missed in it\n",
               path.c_str(), static_cast<unsigned long long>(report.ticks),
               static_cast<unsigned long long>(report.changes),
               static_cast<unsigned long long>(report.samples_compared),
               static_cast<unsigned long long>(report.samples_differing),
               report.stopped_because.c_str(), static_cast<unsigned long long>(report.samples_missed));
  if (!cut_short.empty()) {
    std::fflush(out);
    std::fprintf(err, "hapticd --replay: %s\n", cut_short.c_str());
  }
  const bool differs = report.samples_differing > 0 || report.samples_not_replayed > 0;
  if (differs || (cut_short.empty() && !report.identical())) {
    std::fprintf(out, "first difference: %s\n",
                 !report.first_difference.empty() ? report.first_difference.c_str()
                 : report.samples_not_replayed > 0
                     ? "the recorded shutdown ramp ran longer than the replay's"
                     : "nothing was compared");
    if (report.real_time) {
      std::fprintf(out,
                   "(recorded in REAL_TIME: each change took effect at whatever tick the loop was "
                   "on, and is replayed after the tick it was stamped with; only a LOCKSTEP "
                   "recording is reproduced bit for bit)\n");
    }
    std::fflush(out);
    return kReplayDiffers;
  }
  if (!cut_short.empty()) {
    std::fprintf(out,
                 "what the recording holds is the same, bit for bit, up to where it is cut short; "
                 "the rest of the run is not in it\n");
    std::fflush(out);
    return kReplayCutShort;
  }
  std::fprintf(out, "every force and position is the same, bit for bit\n");
  std::fflush(out);
  return kReplaySame;
}

}  // namespace haptic::recording
