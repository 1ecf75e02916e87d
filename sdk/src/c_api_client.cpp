// The C API (haptic/haptic_c.h): the client, its state stream, the operator and lockstep
// controls, events and the connection.
#include "c_api_internal.hpp"

using namespace haptic::c_api;  // this library's own helpers, for its C entry points

extern "C" {


uint32_t haptic_c_version(void) { return HAPTIC_C_VERSION; }

// ---- client ----

namespace {
haptic_client_config client_config_defaults() {
  haptic_client_config value{};
  haptic_client_config* config = &value;
  const haptic::ClientConfig& d = defaults();
  config->server_address = d.server_address.c_str();
  config->client_name = d.client_name.c_str();
  config->token = "";
  config->tls_ca_file = "";
  config->tls_cert_file = "";
  config->tls_key_file = "";
  config->tls_server_name = "";
  config->udp_address = "";
  config->rpc_timeout_ms = static_cast<uint32_t>(d.rpc_timeout.count());
  config->heartbeat_period_ms = static_cast<uint32_t>(d.heartbeat_period.count());
  config->state_decimation = d.state_decimation;
  config->device_index = d.device_index;
  config->reconnect = d.reconnect;
  config->allow_plaintext_token = d.allow_plaintext_token;
  config->reconnect_backoff_min_ms = static_cast<uint32_t>(d.reconnect_backoff_min.count());
  config->reconnect_backoff_max_ms = static_cast<uint32_t>(d.reconnect_backoff_max.count());
  return value;
}
}  // namespace
HAPTIC_C_INIT(haptic_client_config, client_config_defaults())

int haptic_client_open(const haptic_client_config* config, haptic_client** out, haptic_error* err) {
  return guarded(err, [&] {
    require(out, "ClientConfig", "out");
    *out = nullptr;
    const auto& c = sized<haptic_client_config>(config, "ClientConfig", "config");
    haptic::ClientConfig cpp;
    if (c.server_address != nullptr) cpp.server_address = c.server_address;
    if (c.client_name != nullptr) cpp.client_name = c.client_name;
    cpp.token = text_or_empty(c.token);
    if (!text_or_empty(c.tls_ca_file).empty()) {
      cpp.tls = haptic::TlsOptions{c.tls_ca_file, text_or_empty(c.tls_cert_file),
                                   text_or_empty(c.tls_key_file), text_or_empty(c.tls_server_name)};
    } else if (!text_or_empty(c.tls_cert_file).empty() || !text_or_empty(c.tls_key_file).empty()) {
      throw InvalidArgumentError("ClientConfig: tls_ca_file: needed with tls_cert_file and tls_key_file");
    }
    cpp.udp_address = text_or_empty(c.udp_address);
    cpp.rpc_timeout = std::chrono::milliseconds(c.rpc_timeout_ms);
    cpp.heartbeat_period = std::chrono::milliseconds(c.heartbeat_period_ms);
    cpp.state_decimation = c.state_decimation;
    cpp.device_index = c.device_index;
    cpp.reconnect = c.reconnect != 0;
    cpp.allow_plaintext_token = c.allow_plaintext_token != 0;
    cpp.reconnect_backoff_min = std::chrono::milliseconds(c.reconnect_backoff_min_ms);
    cpp.reconnect_backoff_max = std::chrono::milliseconds(c.reconnect_backoff_max_ms);
    *out = new haptic_client{haptic::Client(std::move(cpp))};
    return HAPTIC_OK;
  });
}

int haptic_client_close(haptic_client* client, haptic_error* err) {
  if (client == nullptr) return guarded(err, [] { return HAPTIC_OK; });
  const int status = guarded(err, [&] {
    client->client.close();
    return HAPTIC_OK;
  });
  // From inside a callback close() refuses (it would wait for its own thread): the client stays.
  if (status == HAPTIC_ERROR_FAILED_PRECONDITION) return status;
  try {
    delete client;  // the destructor swallows its own errors; this catch keeps a surprise out of C
  } catch (...) {
  }
  return status;
}

int haptic_client_device_info(const haptic_client* client, haptic_device_info* out, haptic_error* err) {
  return guarded(err, [&] {
    require(client, "device_info", "client");
    SizedOut<haptic_device_info> written(out, "device_info", "out");
    auto& c = *written;
    const haptic::DeviceInfo& d = client->client.device_info();
    const std::uint32_t size = c.size;
    c = haptic_device_info{};
    c.size = size;
    copy_text(c.name, sizeof(c.name), d.name);
    copy_text(c.model, sizeof(c.model), d.model);
    const haptic::DeviceCapabilities& k = d.capabilities;
    const auto bit = [](bool has, unsigned flag) { return has ? static_cast<std::uint32_t>(flag) : 0u; };
    c.capabilities = bit(k.gravity, HAPTIC_CAPABILITY_GRAVITY) | bit(k.brakes, HAPTIC_CAPABILITY_BRAKES) |
                     bit(k.flexible_modes, HAPTIC_CAPABILITY_FLEXIBLE_MODES) |
                     bit(k.friction, HAPTIC_CAPABILITY_FRICTION) |
                     bit(k.force_sensor, HAPTIC_CAPABILITY_FORCE_SENSOR) |
                     bit(k.quantized_position, HAPTIC_CAPABILITY_QUANTIZED_POSITION) |
                     bit(k.state_estimator, HAPTIC_CAPABILITY_STATE_ESTIMATOR) |
                     bit(k.disturbance_observer, HAPTIC_CAPABILITY_DISTURBANCE_OBSERVER) |
                     bit(k.orientation, HAPTIC_CAPABILITY_ORIENTATION) |
                     bit(k.torque, HAPTIC_CAPABILITY_TORQUE);
    c.dof = d.dof;
    c.workspace_min = to_c(d.workspace_min);
    c.workspace_max = to_c(d.workspace_max);
    c.max_force = d.max_force;
    c.loop_rate_hz = d.loop_rate_hz;
    c.max_torque = d.max_torque;
    c.simulated = d.simulated;
    c.buttons = d.buttons;
    return HAPTIC_OK;
  });
}

uint64_t haptic_client_session_id(const haptic_client* client) {
  if (client == nullptr) return 0;
  try {
    return client->client.session_id();
  } catch (...) {
    return 0;
  }
}

int64_t haptic_client_lease_timeout_ms(const haptic_client* client) {
  if (client == nullptr) return 0;
  try {
    return client->client.lease_timeout().count();
  } catch (...) {
    return 0;
  }
}

// ---- state ----

int haptic_client_poll_state(haptic_client* client, haptic_state* out, uint32_t timeout_ms,
                             haptic_error* err) {
  return guarded(err, [&] {
    require(client, "poll_state", "client");
    sized<haptic_state>(out, "poll_state", "state");
    haptic::State s;
    if (!client->client.poll_state(s, std::chrono::milliseconds(timeout_ms))) return HAPTIC_TIMEOUT;
    copy_state(s, *SizedOut<haptic_state>(out, "poll_state", "state"));
    return HAPTIC_OK;
  });
}

int haptic_client_wait_for_tick(haptic_client* client, uint64_t tick, haptic_state* out,
                                uint32_t timeout_ms, haptic_error* err) {
  return guarded(err, [&] {
    require(client, "wait_for_tick", "client");
    sized<haptic_state>(out, "wait_for_tick", "state");
    haptic::State s;
    if (!client->client.wait_for_tick(tick, s, std::chrono::milliseconds(timeout_ms))) {
      return HAPTIC_TIMEOUT;
    }
    copy_state(s, *SizedOut<haptic_state>(out, "wait_for_tick", "state"));
    return HAPTIC_OK;
  });
}

int haptic_client_subscribe(haptic_client* client, uint32_t decimation, haptic_error* err) {
  return guarded(err, [&] {
    require(client, "Subscribe", "client");
    client->client.subscribe(decimation);
    return HAPTIC_OK;
  });
}

int haptic_client_on_state(haptic_client* client, haptic_state_callback callback, void* user_data,
                           haptic_error* err) {
  return guarded(err, [&] {
    require(client, "on_state", "client");
    if (callback == nullptr) {
      client->client.on_state({});
      return HAPTIC_OK;
    }
    client->client.on_state([callback, user_data](const haptic::State& s) {
      haptic_state c{};
      c.size = sizeof(c);
      copy_state(s, c);
      callback(&c, user_data);
    });
    return HAPTIC_OK;
  });
}

int64_t haptic_steady_clock_ns(void) { return steady_ns(std::chrono::steady_clock::now()); }

int32_t haptic_client_server_time_at(const haptic_client* client, int64_t local_ns, double* out) {
  if (client == nullptr || out == nullptr) return 0;
  try {
    const auto local = std::chrono::steady_clock::time_point(std::chrono::nanoseconds(local_ns));
    const std::optional<double> t = client->client.server_time_at(local);
    if (!t) return 0;
    *out = *t;
    return 1;
  } catch (...) {
    return 0;
  }
}

int32_t haptic_client_clock_offset_ns(const haptic_client* client, int64_t* out) {
  if (client == nullptr || out == nullptr) return 0;
  try {
    const auto offset = client->client.clock_offset();
    if (!offset) return 0;
    *out = offset->count();
    return 1;
  } catch (...) {
    return 0;
  }
}

int32_t haptic_client_clock_drift(const haptic_client* client, double* out) {
  if (client == nullptr || out == nullptr) return 0;
  try {
    const auto drift = client->client.clock_drift();
    if (!drift) return 0;
    *out = *drift;
    return 1;
  } catch (...) {
    return 0;
  }
}

haptic_vec3 haptic_interpolate_position(const haptic_state* a, const haptic_state* b, double t) {
  if (a == nullptr || b == nullptr) return {0.0, 0.0, 0.0};
  return to_c(haptic::interpolate_position(state_of(*a), state_of(*b), t));
}

haptic_vec3 haptic_predict_position(const haptic_state* previous, const haptic_state* latest,
                                    double t) {
  if (previous == nullptr || latest == nullptr) return {0.0, 0.0, 0.0};
  return to_c(haptic::predict_position(state_of(*previous), state_of(*latest), t));
}

int haptic_client_receive_counters(const haptic_client* client, haptic_receive_counters* out,
                                   haptic_error* err) {
  return guarded(err, [&] {
    require(client, "receive_counters", "client");
    SizedOut<haptic_receive_counters> written(out, "receive_counters", "out");
    auto& c = *written;
    const haptic::ReceiveCounters r = client->client.receive_counters();
    c.accepted = r.accepted;
    c.rejected = r.rejected;
    c.skipped = r.skipped;
    c.challenges_answered = r.challenges_answered;
    c.callback_skipped = r.callback_skipped;
    c.lost = r.lost;
    c.reordered = r.reordered;
    c.duplicates = r.duplicates;
    c.reconnects = r.reconnects;
    return HAPTIC_OK;
  });
}

int haptic_client_set_heartbeats_enabled(haptic_client* client, int32_t enabled, haptic_error* err) {
  return guarded(err, [&] {
    require(client, "set_heartbeats_enabled", "client");
    client->client.set_heartbeats_enabled(enabled != 0);
    return HAPTIC_OK;
  });
}


// ---- operator, lockstep ----

namespace {
haptic_operator_input operator_input_defaults() {
  haptic_operator_input value{};
  haptic_operator_input* input = &value;
  const haptic::OperatorInput d;
  input->mode = static_cast<int32_t>(d.mode);
  input->target = to_c(d.target);
  input->stiffness = d.stiffness;
  input->damping = d.damping;
  input->mass = d.mass;
  input->grip = static_cast<int32_t>(d.grip);
  input->path_shape = static_cast<int32_t>(d.path.shape);
  input->path_end = to_c(d.path.end);
  input->path_duration_s = d.path.duration_s;
  input->path_amplitude = to_c(d.path.amplitude);
  input->path_frequency_hz = d.path.frequency_hz;
  input->force = to_c(d.force);
  input->profile_shape = static_cast<int32_t>(d.profile.shape);
  input->profile_repeat = d.profile.repeat;
  input->profile_start_s = d.profile.start_s;
  input->profile_rise_s = d.profile.rise_s;
  input->profile_frequency_hz = d.profile.frequency_hz;
  input->profile_offset = to_c(d.profile.offset);
  input->profile_sample_period_s = d.profile.sample_period_s;
  return value;
}
}  // namespace
HAPTIC_C_INIT(haptic_operator_input, operator_input_defaults())

int haptic_client_set_operator(haptic_client* client, const haptic_operator_input* input,
                               haptic_error* err) {
  return guarded(err, [&] {
    require(client, "SetOperator", "client");
    const auto& c = sized<haptic_operator_input>(input, "SetOperator", "input");
    client->client.set_operator(converting("SetOperator", "input", [&] { return operator_of(c); }));
    return HAPTIC_OK;
  });
}

int haptic_client_set_operator_push(haptic_client* client, haptic_vec3 force, haptic_error* err) {
  return guarded(err, [&] {
    require(client, "SetOperator", "client");
    client->client.set_operator(haptic::OperatorInput::push(to_cpp(force)));
    return HAPTIC_OK;
  });
}

int haptic_client_set_operator_follow(haptic_client* client, haptic_vec3 target, double stiffness,
                                      double damping, haptic_error* err) {
  return guarded(err, [&] {
    require(client, "SetOperator", "client");
    client->client.set_operator(haptic::OperatorInput::follow(to_cpp(target), stiffness, damping));
    return HAPTIC_OK;
  });
}

int haptic_client_step(haptic_client* client, uint32_t ticks, uint64_t* last_tick, haptic_error* err) {
  return guarded(err, [&] {
    require(client, "Step", "client");
    const std::uint64_t last = client->client.step(ticks);
    if (last_tick != nullptr) *last_tick = last;
    return HAPTIC_OK;
  });
}

int haptic_client_reset(haptic_client* client, haptic_error* err) {
  return guarded(err, [&] {
    require(client, "Reset", "client");
    client->client.reset();
    return HAPTIC_OK;
  });
}

// ---- events, connection ----

int haptic_client_on_event(haptic_client* client, haptic_event_callback callback, void* user_data,
                           haptic_error* err) {
  return guarded(err, [&] {
    require(client, "WatchEvents", "client");
    if (callback == nullptr) {
      client->client.on_event({});
      return HAPTIC_OK;
    }
    client->client.on_event([callback, user_data](const haptic::Event& e) {
      haptic_event c{};
      c.size = sizeof(c);
      c.kind = static_cast<int32_t>(e.kind);
      c.session_id = e.session_id;
      c.item_id = e.item_id;
      c.server_time = e.server_time;
      c.message = e.message.c_str();
      callback(&c, user_data);
    });
    return HAPTIC_OK;
  });
}

int haptic_client_on_connection(haptic_client* client, haptic_connection_callback callback,
                                void* user_data, haptic_error* err) {
  return guarded(err, [&] {
    require(client, "on_connection", "client");
    if (callback == nullptr) {
      client->client.on_connection({});
      return HAPTIC_OK;
    }
    client->client.on_connection([callback, user_data](const haptic::ConnectionChange& change) {
      haptic_connection_change c{};
      c.size = sizeof(c);
      c.state = static_cast<int32_t>(change.state);
      c.session_id = change.session_id;
      c.new_session = change.new_session;
      c.items_not_restored = change.items_not_restored;
      c.outage_ms = change.outage.count();
      c.reason = change.reason.c_str();
      callback(&c, user_data);
    });
    return HAPTIC_OK;
  });
}

int32_t haptic_client_connection_state(const haptic_client* client) {
  if (client == nullptr) return HAPTIC_CONNECTION_ENDED;
  try {
    return static_cast<int32_t>(client->client.connection_state());
  } catch (...) {
    return HAPTIC_CONNECTION_ENDED;
  }
}


}  // extern "C"
