#include "app/replay.hpp"

#include <grpcpp/grpcpp.h>

#include <algorithm>
#include <bit>
#include <cstdio>
#include <map>
#include <utility>

#include "app/server.hpp"
#include "config/server_config.hpp"
#include "haptic/io/session_secret.hpp"
#include "haptic/v1/recording.pb.h"
#include "haptic/v1/service.grpc.pb.h"
#include "net/recording_file.hpp"
#include "schema/scene_specs.hpp"

namespace haptic::app {
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

std::string vec_text(const v1::Vec3& v) {
  char text[160];
  std::snprintf(text, sizeof text, "(%.17g, %.17g, %.17g)", v.x(), v.y(), v.z());
  return text;
}

bool same_bits(const v1::Vec3& recorded, const engine::Vec3& replayed) {
  return std::bit_cast<std::uint64_t>(recorded.x()) == std::bit_cast<std::uint64_t>(replayed.x) &&
         std::bit_cast<std::uint64_t>(recorded.y()) == std::bit_cast<std::uint64_t>(replayed.y) &&
         std::bit_cast<std::uint64_t>(recorded.z()) == std::bit_cast<std::uint64_t>(replayed.z);
}

class Replay {
 public:
  explicit Replay(const v1::RecordHeader& header)
      : server_(replay_config(header)) {
    server_.start();
    stub_ = v1::Haptic::NewStub(grpc::CreateChannel("127.0.0.1:" + std::to_string(server_.grpc_port()),
                                                    grpc::InsecureChannelCredentials()));
    // A session of the replay's own steps the loop (stepping is no recorded client's change).
    stepper_ = open("hapticd-replay", 0);
  }
  ~Replay() { server_.shutdown(); }

  /// The recorded server's shutdown: the same ramp to zero, its ticks kept for comparison.
  void shut_down() {
    server_.shutdown();
    shut_down_ = true;
    for (std::uint64_t t = completed_ + 1;; ++t) {
      bool any = false;
      for (std::size_t port = 0; port < server_.device_ports(); ++port) {
        runtime::TickSample sample;
        if (server_.samples(port).read(t, sample)) {
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
        for (std::size_t port = 0; port < server_.device_ports(); ++port) {
          runtime::TickSample sample;
          if (server_.samples(port).read(t, sample)) replayed_[{t, port}] = sample;
        }
      }
      completed_ = reply.tick();
      report_.ticks = completed_;
      if (progress_ && completed_ / 10000 != (completed_ - request.ticks()) / 10000) progress_(completed_);
    }
  }

  void compare(const v1::RecordedSample& recorded) {
    advance_to(recorded.tick());
    const auto found = replayed_.find({recorded.tick(), recorded.port()});
    if (found == replayed_.end() && shut_down_) {
      ++report_.samples_not_replayed;  // the recorded ramp ran longer than the replay's
      return;
    }
    if (found == replayed_.end()) {
      throw ReplayError("tick " + std::to_string(recorded.tick()) + " port " +
                        std::to_string(recorded.port()) + ": the replay has no such sample (is the "
                        "recording's configuration another device?)");
    }
    const runtime::TickSample& replayed = found->second;
    ++report_.samples_compared;
    const bool force_same = same_bits(recorded.force(), replayed.F_T_W);
    const bool position_same = same_bits(recorded.position(), replayed.p_WT);
    if (!force_same || !position_same) {
      if (report_.samples_differing == 0) {
        const char* what = force_same ? "position" : "force";
        report_.first_difference =
            "tick " + std::to_string(recorded.tick()) + " port " + std::to_string(recorded.port()) +
            ": " + what + " recorded " +
            vec_text(force_same ? recorded.position() : recorded.force()) + ", replayed " +
            vec_text(schema::to_proto(force_same ? replayed.p_WT : replayed.F_T_W));
      }
      ++report_.samples_differing;
    }
    // What is compared is done with; anything older than a ring behind never will be.
    replayed_.erase(found);
    while (!replayed_.empty() &&
           replayed_.begin()->first.first + runtime::SampleRing::kCapacity < recorded.tick()) {
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

  Server server_;
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

ReplayReport replay_recording(const std::string& path,
                              const std::function<void(std::uint64_t ticks)>& progress) {
  std::unique_ptr<net::RecordingReader> reader;
  try {
    reader = std::make_unique<net::RecordingReader>(path);
  } catch (const std::exception& error) {
    throw ReplayError(error.what());
  }
  v1::Record record;
  if (!reader->next(record) || !record.has_header() ||
      record.header().format() != "hapticd-recording") {
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
  if (const std::string error = config::validate(replay_config(header)); !error.empty()) {
    throw ReplayError("'" + path + "': its configuration does not validate here: " + error);
  }
  Replay replay(header);
  replay.on_progress(progress);
  replay.report().real_time = header.config().time_mode() != v1::LOCKSTEP;
  bool ended = false;
  while (reader->next(record)) {
    if (record.has_sample()) {
      replay.compare(record.sample());
    } else if (record.has_change()) {
      replay.apply(record.change());
    } else if (record.has_end()) {
      replay.report().samples_missed = record.end().samples_missed();
      replay.report().stopped_because = record.end().stopped_because();
      ended = true;
      break;
    }
  }
  if (!ended) {
    // A recorder killed with its server leaves no end record, and perhaps a block cut short:
    // what was written is replayed all the same.
    replay.report().stopped_because =
        "the file ends without an end record (" +
        (reader->error().empty() ? std::string("the recording server was killed?") : reader->error()) +
        "): replayed as far as it goes";
  }
  return replay.report();
}

}  // namespace haptic::app
