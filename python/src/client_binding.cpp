// haptic::Client and its handles in Python. Every call that waits on the server or on the SDK's
// threads lets go of the GIL first, so the SDK's threads can run Python callbacks meanwhile; the
// destructors of Client and of the handles do the same (DeleteWithoutGil).

#include <pybind11/stl.h>

#include <chrono>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <unordered_set>
#include <utility>
#include <variant>
#include <vector>

#include "bindings.hpp"
#include "binding_support.hpp"
#include "haptic/haptic.hpp"

namespace haptic::python {

namespace {

/// Every Client alive in this process, so that the interpreter's exit can close them first
/// (atexit): a Python callback still running when the interpreter finalizes would be cut off
/// mid-call on the SDK's thread, and the process would crash.
class LiveClients {
 public:
  void add(Client* client) {
    std::lock_guard lock(mutex_);
    clients_.insert(client);
  }
  void remove(Client* client) {
    std::lock_guard lock(mutex_);
    clients_.erase(client);
  }
  /// Closes each (called with the GIL, from atexit, once the program's own threads have ended);
  /// a refusal from the server is ignored, as the destructor would.
  void close_all() {
    std::vector<Client*> open;
    {
      std::lock_guard lock(mutex_);
      open.assign(clients_.begin(), clients_.end());
    }
    py::gil_scoped_release released;
    for (Client* client : open) {
      try {
        client->close();
      } catch (const std::exception&) {
      }
    }
  }

 private:
  std::mutex mutex_;
  std::unordered_set<Client*> clients_;
};

LiveClients& live_clients() {
  static auto* clients = new LiveClients;  // never destroyed: atexit may run after statics go
  return *clients;
}

/// Deletes a Client without the GIL, after taking it off the live list.
struct DeleteClient {
  void operator()(Client* client) const {
    live_clients().remove(client);
    DeleteWithoutGil<Client>{}(client);
  }
};

using ClientHolder = std::unique_ptr<Client, DeleteClient>;
using ReleaseGil = py::call_guard<py::gil_scoped_release>;

/// The handles of a scene applied whole, each a Python ObjectHandle or FieldHandle.
struct AppliedSceneHandles {
  py::list objects;
  py::list fields;
};

AppliedSceneHandles to_python(AppliedScene&& applied) {
  AppliedSceneHandles handles;
  for (ObjectHandle& object : applied.objects) handles.objects.append(py::cast(std::move(object)));
  for (FieldHandle& field : applied.fields) handles.fields.append(py::cast(std::move(field)));
  return handles;
}

/// `with value:` returns the value itself and calls `finish(value)` without the GIL at the end
/// of the block (an exception from the block goes on).
template <class T, class Holder, class Finish>
void def_context_manager(py::class_<T, Holder>& cls, Finish finish, const char* doc) {
  cls.def("__enter__", [](py::object self) { return self; })
      .def(
          "__exit__",
          [finish](T& value, const py::args&) {
            py::gil_scoped_release released;
            finish(value);
            return false;
          },
          doc);
}

/// What ObjectHandle and FieldHandle share (detail::ItemHandle), plus the context-manager
/// protocol: leaving a `with` block removes the item.
template <class Handle, class Holder>
void bind_item_handle(py::class_<Handle, Holder>& cls) {
  // Lambdas, not member pointers: those name detail::ItemHandle, which Python does not know.
  cls.def_property_readonly(
         "id", [](const Handle& h) { return h.id(); },
         "The item's id on the server now; 0 when the handle owns nothing.")
      .def_property_readonly(
          "owned", [](const Handle& h) { return h.owned(); },
          "True while this handle will remove the item.")
      .def(
          "remove", [](Handle& h) { h.remove(); }, ReleaseGil(),
          "Removes the item now (its force ramps out). Raises hapticd.Error.")
      .def(
          "release", [](Handle& h) { return h.release(); },
          "Stops owning the item (it stays until the session ends); returns its id.")
      .def("__repr__", [](const py::object& self) {
        const Handle& handle = self.cast<const Handle&>();
        return py::str("{}(id={}, owned={})")
            .format(py::type::of(self).attr("__name__"), handle.id(), handle.owned());
      });
  def_context_manager(cls, [](Handle& handle) { handle.remove(); }, "Removes the item.");
}

/// Binds `handle.update(spec)` for each spec type in Specs.
template <class... Specs, class Handle, class Holder>
void def_updates(py::class_<Handle, Holder>& cls, const char* doc) {
  (cls.def(
       "update", [](Handle& handle, const Specs& spec) { handle.update(spec); }, py::arg("spec"),
       ReleaseGil(), doc),
   ...);
}

/// Binds `client.<name>(spec)` for each spec type in Specs to `add`.
template <class... Specs, class Add>
void def_adders(py::class_<Client, ClientHolder>& cls, const char* name, Add add, const char* doc) {
  (cls.def(name, [add](Client& client, const Specs& spec) {
     auto handle = [&] {
       py::gil_scoped_release released;
       return add(client, spec);
     }();
     return handle;
   }, py::arg("spec"), doc),
   ...);
}

/// `base` (or the defaults) with any of its fields replaced by keyword.
ClientConfig config_from(std::optional<ClientConfig> base, const py::kwargs& overrides) {
  ClientConfig config = base.value_or(ClientConfig{});
  assign_fields(py::cast(&config, py::return_value_policy::reference), overrides,
                "Client() has no option");
  return config;
}

/// Runs `wait` without the GIL for up to `timeout_s` seconds: its State, or None.
std::optional<State> wait_for_state(
    double timeout_s, const std::function<bool(State&, std::chrono::milliseconds)>& wait) {
  const std::chrono::milliseconds timeout = milliseconds_from_seconds(timeout_s, "timeout");
  State state;
  py::gil_scoped_release released;
  if (!wait(state, timeout)) return std::nullopt;
  return state;
}

void bind_config(py::module_& m) {
  StructBinder<TlsOptions>(m, "TlsOptions", "TLS for the control plane (docs/deployment.md).")
      .field("ca_file", &TlsOptions::ca_file, "PEM: the CA that signed the server's certificate")
      .field("cert_file", &TlsOptions::cert_file, "PEM: this client's certificate (mTLS)")
      .field("key_file", &TlsOptions::key_file, "PEM: its private key")
      .field("server_name", &TlsOptions::server_name, "default: the host of server_address")
      .finish();
  const auto duration = [](std::chrono::milliseconds ClientConfig::*member, const char* name) {
    return std::pair{[member](const ClientConfig& c) { return seconds(c.*member); },
                     [member, name](ClientConfig& c, double value) {
                       c.*member = milliseconds_from_seconds(value, name);
                     }};
  };
  const auto [rpc_get, rpc_set] = duration(&ClientConfig::rpc_timeout, "ClientConfig.rpc_timeout");
  const auto [beat_get, beat_set] =
      duration(&ClientConfig::heartbeat_period, "ClientConfig.heartbeat_period");
  const auto [min_get, min_set] =
      duration(&ClientConfig::reconnect_backoff_min, "ClientConfig.reconnect_backoff_min");
  const auto [max_get, max_set] =
      duration(&ClientConfig::reconnect_backoff_max, "ClientConfig.reconnect_backoff_max");
  StructBinder<ClientConfig>(m, "ClientConfig", "How a Client connects. Durations in seconds.")
      .field("server_address", &ClientConfig::server_address, "gRPC host:port of hapticd")
      .field("tls", &ClientConfig::tls, "TlsOptions, or None for plaintext")
      .field("token", &ClientConfig::token,
             "the bearer token the server gave this client; sent only over TLS or to loopback")
      .field("allow_plaintext_token", &ClientConfig::allow_plaintext_token,
             "send the token in clear to another host all the same (a trusted network)")
      .field("client_name", &ClientConfig::client_name, "1..64 printable characters")
      .property("rpc_timeout", rpc_get, rpc_set, "deadline of every control-plane call, s")
      .property("heartbeat_period", beat_get, beat_set, "UDP heartbeat period, s")
      .field("state_decimation", &ClientConfig::state_decimation, "state every n-th tick; 0: none")
      .field("lockstep_flow_control", &ClientConfig::lockstep_flow_control,
             "acknowledge what was read, so a lockstep Step of any length arrives whole")
      .field("udp_address", &ClientConfig::udp_address, "host:port to send datagrams to instead")
      .field("device_index", &ClientConfig::device_index, "the server's device port to use")
      .field("reconnect", &ClientConfig::reconnect, "reconnect on its own after a loss")
      .property("reconnect_backoff_min", min_get, min_set, "s")
      .property("reconnect_backoff_max", max_get, max_set, "s")
      .finish();
}

void bind_handles(py::module_& m) {
  py::class_<ObjectHandle, std::unique_ptr<ObjectHandle, DeleteWithoutGil<ObjectHandle>>> object(
      m, "ObjectHandle",
      "A registered object. Removes it when garbage-collected, when remove() is called, or at the "
      "end of a `with` block; release() keeps it for the session's life.");
  bind_item_handle(object);
  object.def_property_readonly("stability", &ObjectHandle::stability,
                               py::return_value_policy::copy,
                               "StabilityReport for the impedance as registered or last updated.");
  def_updates<WallSpec, SphereSpec, BoxSpec, CapsuleSpec, TangentPlaneSpec, MeshSpec>(
      object, "Replaces the object with `spec` (any object kind); on an error the old one stays.");

  py::class_<FieldHandle, std::unique_ptr<FieldHandle, DeleteWithoutGil<FieldHandle>>> field(
      m, "FieldHandle", "A registered energy field; owned as ObjectHandle's object is.");
  bind_item_handle(field);
  def_updates<SpringFieldSpec, DistanceSpringSpec, PotentialFieldSpec, LinearFieldSpec,
              ViscousFieldSpec, DetentFieldSpec, OrientationSpringSpec, OrientationDetentSpec>(
      field, "Replaces the field with `spec` (any field kind); on an error the old one stays.");

  py::class_<AppliedSceneHandles>(m, "AppliedScene",
                                  "The handles of a scene applied whole, in the scene's order; "
                                  "a `with` block removes them all at its end.")
      .def_readonly("objects", &AppliedSceneHandles::objects, "list of ObjectHandle")
      .def_readonly("fields", &AppliedSceneHandles::fields, "list of FieldHandle")
      .def("__enter__", [](py::object self) { return self; })
      .def("__exit__", [](AppliedSceneHandles& self, const py::args&) {
        for (const py::handle& handle : self.objects) handle.attr("remove")();
        for (const py::handle& handle : self.fields) handle.attr("remove")();
        return false;
      })
      .def("__repr__", [](const AppliedSceneHandles& self) {
        return py::str("AppliedScene({} objects, {} fields)")
            .format(py::len(self.objects), py::len(self.fields));
      });
}

void bind_client_class(py::module_& m) {
  py::class_<Client, ClientHolder> cls(
      m, "Client",
      "One session with a hapticd server. Client(config) or Client(server_address=..., ...): any "
      "ClientConfig field by keyword. Usable as a context manager (closes at the end).");
  cls.def(py::init([](std::optional<ClientConfig> config, const py::kwargs& overrides) {
            ClientConfig chosen = config_from(std::move(config), overrides);
            ClientHolder client = [&] {
              py::gil_scoped_release released;
              return ClientHolder(new Client(std::move(chosen)));
            }();
            live_clients().add(client.get());
            return client;
          }),
          py::arg("config") = py::none(),
          "Connects and opens a session. Raises ConnectionError, VersionMismatchError, "
          "InvalidArgumentError, ResourceExhaustedError.");

  def_adders<WallSpec>(cls, "add_wall", [](Client& c, const WallSpec& s) { return c.add_wall(s); },
                       "Registers a wall; returns its ObjectHandle.");
  def_adders<SphereSpec>(cls, "add_sphere",
                         [](Client& c, const SphereSpec& s) { return c.add_sphere(s); },
                         "Registers a sphere; returns its ObjectHandle.");
  def_adders<BoxSpec>(cls, "add_box", [](Client& c, const BoxSpec& s) { return c.add_box(s); },
                      "Registers a box; returns its ObjectHandle.");
  def_adders<CapsuleSpec>(cls, "add_capsule",
                          [](Client& c, const CapsuleSpec& s) { return c.add_capsule(s); },
                          "Registers a capsule; returns its ObjectHandle.");
  def_adders<TangentPlaneSpec>(
      cls, "add_tangent_plane",
      [](Client& c, const TangentPlaneSpec& s) { return c.add_tangent_plane(s); },
      "Registers a tangent-plane local model; returns its ObjectHandle.");
  def_adders<MeshSpec>(cls, "add_mesh", [](Client& c, const MeshSpec& s) { return c.add_mesh(s); },
                       "Registers a triangle mesh (validated in full by the server).");
  def_adders<SpringFieldSpec>(
      cls, "add_spring_field",
      [](Client& c, const SpringFieldSpec& s) { return c.add_spring_field(s); },
      "Registers a spring field; returns its FieldHandle.");
  const auto add_field = [](Client& c, const auto& spec) { return c.add_field(spec); };
  def_adders<DistanceSpringSpec, PotentialFieldSpec, LinearFieldSpec, ViscousFieldSpec,
             DetentFieldSpec, OrientationSpringSpec, OrientationDetentSpec>(
      cls, "add_field", add_field, "Registers an energy field; returns its FieldHandle.");
  def_adders<SpringFieldSpec>(
      cls, "add_field", [](Client& c, const SpringFieldSpec& s) { return c.add_spring_field(s); },
      "Registers a spring field; returns its FieldHandle.");

  const auto add_any = [](Client& c, const auto& spec) {
    using Spec = std::decay_t<decltype(spec)>;
    if constexpr (std::is_same_v<Spec, WallSpec>) return c.add_wall(spec);
    else if constexpr (std::is_same_v<Spec, SphereSpec>) return c.add_sphere(spec);
    else if constexpr (std::is_same_v<Spec, BoxSpec>) return c.add_box(spec);
    else if constexpr (std::is_same_v<Spec, CapsuleSpec>) return c.add_capsule(spec);
    else if constexpr (std::is_same_v<Spec, TangentPlaneSpec>) return c.add_tangent_plane(spec);
    else if constexpr (std::is_same_v<Spec, MeshSpec>) return c.add_mesh(spec);
    else if constexpr (std::is_same_v<Spec, SpringFieldSpec>) return c.add_spring_field(spec);
    else return c.add_field(spec);
  };
  def_adders<WallSpec, SphereSpec, BoxSpec, CapsuleSpec, TangentPlaneSpec, MeshSpec,
             SpringFieldSpec, DistanceSpringSpec, PotentialFieldSpec, LinearFieldSpec,
             ViscousFieldSpec, DetentFieldSpec, OrientationSpringSpec, OrientationDetentSpec>(
      cls, "add", add_any,
      "Registers any object or field spec; returns its ObjectHandle or FieldHandle.");

  cls.def(
         "apply_scene",
         [](Client& client, const SceneSpec& scene) {
           auto applied = [&] {
             py::gil_scoped_release released;
             return client.apply_scene(scene);
           }();
           return to_python(std::move(applied));
         },
         py::arg("scene"),
         "Replaces this session's objects and fields at once (all or nothing); returns an "
         "AppliedScene. Earlier handles go stale.")
      .def(
          "apply_scene_file",
          [](Client& client, const std::string& path) {
            auto applied = [&] {
              py::gil_scoped_release released;
              return client.apply_scene_file(path);
            }();
            return to_python(std::move(applied));
          },
          py::arg("path"), "The same from a scene file (protobuf JSON, as hapticd --scene reads).")
      .def_property_readonly("last_scene_stability", &Client::last_scene_stability,
                             py::return_value_policy::copy,
                             "StabilityReports of the last applied scene's objects, in order.")
      .def("scene_energy", &Client::scene_energy, ReleaseGil(),
           "Energy every object and field has exchanged with the device: list of ItemEnergy.")
      .def("object_states", &Client::object_states, ReleaseGil(),
           "Every virtual mass and where it is now: list of ObjectState.")
      .def("scene", &Client::scene, py::arg("all_sessions") = false, ReleaseGil(),
           "This session's objects and fields as the server holds them (RegisteredScene); "
           "with all_sessions, every session's and the server's own.")
      .def("set_operator", &Client::set_operator, py::arg("input"), ReleaseGil(),
           "Sets what the server's simulated operator does (OperatorInput).")
      .def("step", &Client::step, py::arg("ticks") = 1, ReleaseGil(),
           "Lockstep servers only: runs `ticks` ticks; returns the last one's index.")
      .def("reset", &Client::reset, ReleaseGil(),
           "Lockstep, simulated devices only: puts the server back as it started.")
      .def("subscribe", &Client::subscribe, py::arg("decimation"), ReleaseGil(),
           "Changes the state stream's decimation (every n-th tick; 0 stops it).")
      .def_property_readonly("device_info", &Client::device_info, py::return_value_policy::copy,
                             "DeviceInfo, as reported when the session opened.")
      .def("stats", &Client::stats, ReleaseGil(), "The server's counters (ADMIN token with tokens).")
      .def("sessions", &Client::sessions, ReleaseGil(), "Every open session (ADMIN).")
      .def("kick_session", &Client::kick_session, py::arg("session_id"), py::arg("reason") = "",
           ReleaseGil(), "Ends another session (ADMIN).")
      .def("start_recording", &Client::start_recording, py::arg("name"), ReleaseGil(),
           "Starts recording the run on the server, for hapticd --replay (ADMIN).")
      .def("stop_recording", &Client::stop_recording, ReleaseGil(), "Stops it, with its totals.")
      .def_property_readonly("session_id", &Client::session_id, "The session's id now.")
      .def_property_readonly(
          "lease_timeout", [](const Client& c) { return seconds(c.lease_timeout()); },
          "How long the server keeps a silent session, s.");

  cls.def(
         "on_state",
         [](Client& client, const py::object& callback) {
           auto call = sdk_callback<State>(callback, "hapticd.Client.on_state callback");
           py::gil_scoped_release released;
           client.on_state(std::move(call));
         },
         py::arg("callback"),
         "Calls callback(state) on the SDK's receive thread with the newest State as it arrives "
         "(holding the GIL while it runs); None stops it.")
      .def(
          "on_event",
          [](Client& client, const py::object& callback) {
            auto call = sdk_callback<Event>(callback, "hapticd.Client.on_event callback");
            py::gil_scoped_release released;
            client.on_event(std::move(call));
          },
          py::arg("callback"), "Calls callback(event) with each server Event; None stops it.")
      .def(
          "on_connection",
          [](Client& client, const py::object& callback) {
            auto call =
                sdk_callback<ConnectionChange>(callback, "hapticd.Client.on_connection callback");
            py::gil_scoped_release released;
            client.on_connection(std::move(call));
          },
          py::arg("callback"),
          "Calls callback(change) when the connection is lost and when it resumes; None stops it.")
      .def(
          "poll_state",
          [](Client& client, double timeout_s) {
            return wait_for_state(timeout_s, [&client](State& out, std::chrono::milliseconds t) {
              return client.poll_state(out, t);
            });
          },
          py::arg("timeout") = 1.0,
          "Waits up to timeout s for a sample newer than the last one returned: a State, or None.")
      .def(
          "wait_for_tick",
          [](Client& client, std::uint64_t tick, double timeout_s) {
            return wait_for_state(timeout_s, [&client, tick](State& out, std::chrono::milliseconds t) {
              return client.wait_for_tick(tick, out, t);
            });
          },
          py::arg("tick"), py::arg("timeout") = 5.0,
          "Waits up to timeout s for a sample of tick >= `tick`: the newest State, or None.")
      .def(
          "clock_offset",
          [](const Client& c) -> std::optional<double> {
            const auto offset = c.clock_offset();
            if (!offset) return std::nullopt;
            return std::chrono::duration<double>(*offset).count();
          },
          "Server clock − local monotonic clock, s; None before any sample.")
      .def("clock_drift", &Client::clock_drift,
           "How much faster the server's clock runs (5e-5 is 50 ppm); None until known.")
      .def(
          "server_time_at",
          [](const Client& c, std::optional<double> local) -> std::optional<double> {
            const auto at = local ? std::chrono::steady_clock::time_point(
                                        std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                            std::chrono::duration<double>(*local)))
                                  : std::chrono::steady_clock::now();
            return c.server_time_at(at);
          },
          py::arg("local") = py::none(),
          "The server's time (s) at local time `local` (time.monotonic() seconds; default now).")
      .def_property_readonly("connection_state", &Client::connection_state,
                             "ConnectionChange.State")
      .def("set_heartbeats_enabled", &Client::set_heartbeats_enabled, py::arg("enabled"),
           ReleaseGil(), "Stops or resumes UDP heartbeats (stopping simulates a lost client).")
      .def("receive_counters", &Client::receive_counters, "ReceiveCounters")
      .def("close", &Client::close, ReleaseGil(),
           "Closes the session now; raises hapticd.Error if the server refuses.");
  def_context_manager(
      cls,
      [](Client& client) {
        // A server that cannot be reached is not an error on leaving the block: the session ends
        // there when its lease runs out, and raising here would hide the block's own exception.
        try {
          client.close();
        } catch (const ConnectionError&) {
        }
      },
      "Closes the session; a server that cannot be reached (stopped, restarting) ends it itself "
      "when its lease runs out, so leaving the block does not raise for that.");
}

}  // namespace

void bind_client(py::module_& m) {
  bind_config(m);
  bind_handles(m);
  bind_client_class(m);
  py::module_::import("atexit").attr("register")(
      py::cpp_function([] { live_clients().close_all(); }, py::name("_close_clients_at_exit")));

  m.attr("API_VERSION") = kApiVersion;
  m.def("scene_json", &scene_json, py::arg("scene"),
        "`scene` as a scene file's text (protobuf JSON), as apply_scene_file and hapticd --scene "
        "read it.");
  m.def("interpolate_position", &interpolate_position, py::arg("a"), py::arg("b"), py::arg("t"),
        "The position at server time t between States a and b (cubic Hermite), m.");
  m.def("predict_position", &predict_position, py::arg("previous"), py::arg("latest"),
        py::arg("t"), "The position at server time t >= latest's, extrapolated, m.");
}

}  // namespace haptic::python
