// The C API (haptic/haptic_c.h) over haptic::Client: every entry point catches every exception
// and reports it as a code and message, so nothing unwinds into C.

#include "haptic/haptic_c.h"

#include <chrono>
#include <cstring>
#include <exception>
#include <new>
#include <optional>
#include <string>

#include "haptic/haptic.hpp"

struct haptic_client {
  haptic::Client client;
};

struct haptic_object {
  haptic::ObjectHandle handle;
};

namespace {

void set_error(haptic_error* err, int code, const char* message) {
  if (err == nullptr) return;
  err->code = code;
  std::strncpy(err->message, message, HAPTIC_ERROR_MESSAGE_SIZE - 1);
  err->message[HAPTIC_ERROR_MESSAGE_SIZE - 1] = '\0';
}

int code_of(haptic::ErrorCode code) {
  switch (code) {
    case haptic::ErrorCode::kConnection: return HAPTIC_ERROR_CONNECTION;
    case haptic::ErrorCode::kInvalidArgument: return HAPTIC_ERROR_INVALID_ARGUMENT;
    case haptic::ErrorCode::kNotFound: return HAPTIC_ERROR_NOT_FOUND;
    case haptic::ErrorCode::kPermissionDenied: return HAPTIC_ERROR_PERMISSION_DENIED;
    case haptic::ErrorCode::kResourceExhausted: return HAPTIC_ERROR_RESOURCE_EXHAUSTED;
    case haptic::ErrorCode::kFailedPrecondition: return HAPTIC_ERROR_FAILED_PRECONDITION;
    case haptic::ErrorCode::kVersionMismatch: return HAPTIC_ERROR_VERSION_MISMATCH;
    case haptic::ErrorCode::kInternal: return HAPTIC_ERROR_INTERNAL;
    case haptic::ErrorCode::kUnauthenticated: return HAPTIC_ERROR_UNAUTHENTICATED;
  }
  return HAPTIC_ERROR_INTERNAL;
}

// Runs `body` (which returns a status), mapping whatever it throws onto `err`.
template <typename Body>
int guarded(haptic_error* err, Body&& body) noexcept {
  try {
    set_error(err, HAPTIC_OK, "");
    return body();
  } catch (const haptic::Error& e) {
    set_error(err, code_of(e.code()), e.what());
    return code_of(e.code());
  } catch (const std::bad_alloc&) {
    set_error(err, HAPTIC_ERROR_INTERNAL, "out of memory");
    return HAPTIC_ERROR_INTERNAL;
  } catch (const std::exception& e) {
    set_error(err, HAPTIC_ERROR_INTERNAL, e.what());
    return HAPTIC_ERROR_INTERNAL;
  } catch (...) {
    set_error(err, HAPTIC_ERROR_INTERNAL, "unknown error");
    return HAPTIC_ERROR_INTERNAL;
  }
}

int invalid(haptic_error* err, const char* message) {
  set_error(err, HAPTIC_ERROR_INVALID_ARGUMENT, message);
  return HAPTIC_ERROR_INVALID_ARGUMENT;
}

const haptic::ClientConfig& defaults() {
  static const haptic::ClientConfig config;
  return config;
}

haptic_vec3 to_c(const haptic::Vec3& v) { return {v.x, v.y, v.z}; }
haptic::Vec3 from_c(const haptic_vec3& v) { return {v.x, v.y, v.z}; }

void copy_state(const haptic::State& s, haptic_state* out) {
  out->tick = s.tick;
  out->sequence = s.sequence;
  out->server_time = s.server_time;
  out->position = to_c(s.position);
  out->velocity = to_c(s.velocity);
  out->force = to_c(s.force);
  out->proxy = to_c(s.proxy);
  out->contact_count = s.contact_count;
  out->flags = s.flags;
  out->buttons = s.buttons;
}

}  // namespace

extern "C" {

uint32_t haptic_c_version(void) { return HAPTIC_C_VERSION; }

void haptic_client_config_init(haptic_client_config* config) {
  if (config == nullptr) return;
  const haptic::ClientConfig& d = defaults();
  *config = haptic_client_config{};
  config->size = sizeof(haptic_client_config);
  config->server_address = d.server_address.c_str();
  config->client_name = d.client_name.c_str();
  config->token = d.token.c_str();
  config->rpc_timeout_ms = static_cast<uint32_t>(d.rpc_timeout.count());
  config->heartbeat_period_ms = static_cast<uint32_t>(d.heartbeat_period.count());
  config->state_decimation = d.state_decimation;
  config->device_index = d.device_index;
  config->reconnect = d.reconnect ? 1 : 0;
}

int haptic_client_open(const haptic_client_config* config, haptic_client** out, haptic_error* err) {
  if (out == nullptr) return invalid(err, "haptic_client_open: out: is NULL");
  *out = nullptr;
  if (config == nullptr) return invalid(err, "ClientConfig: config: is NULL");
  if (config->size < sizeof(haptic_client_config)) {
    return invalid(err, "ClientConfig: size: smaller than version 1's haptic_client_config");
  }
  return guarded(err, [&] {
    haptic::ClientConfig c;
    if (config->server_address != nullptr) c.server_address = config->server_address;
    if (config->client_name != nullptr) c.client_name = config->client_name;
    if (config->token != nullptr) c.token = config->token;
    c.rpc_timeout = std::chrono::milliseconds(config->rpc_timeout_ms);
    c.heartbeat_period = std::chrono::milliseconds(config->heartbeat_period_ms);
    c.state_decimation = config->state_decimation;
    c.device_index = config->device_index;
    c.reconnect = config->reconnect != 0;
    *out = new haptic_client{haptic::Client(std::move(c))};
    return HAPTIC_OK;
  });
}

void haptic_client_close(haptic_client* client) {
  // The Client's destructor swallows its own errors; this catch keeps a surprise out of C.
  try {
    delete client;
  } catch (...) {
  }
}

int haptic_client_poll_state(haptic_client* client, haptic_state* out, uint32_t timeout_ms,
                             haptic_error* err) {
  if (client == nullptr) return invalid(err, "poll_state: client: is NULL");
  if (out == nullptr || out->size < sizeof(haptic_state)) {
    return invalid(err, "poll_state: state: NULL or size smaller than version 1's haptic_state");
  }
  return guarded(err, [&] {
    haptic::State s;
    if (!client->client.poll_state(s, std::chrono::milliseconds(timeout_ms))) return HAPTIC_TIMEOUT;
    copy_state(s, out);
    return HAPTIC_OK;
  });
}

int haptic_client_wait_for_tick(haptic_client* client, uint64_t tick, haptic_state* out,
                                uint32_t timeout_ms, haptic_error* err) {
  if (client == nullptr) return invalid(err, "wait_for_tick: client: is NULL");
  if (out == nullptr || out->size < sizeof(haptic_state)) {
    return invalid(err, "wait_for_tick: state: NULL or size smaller than version 1's haptic_state");
  }
  return guarded(err, [&] {
    haptic::State s;
    if (!client->client.wait_for_tick(tick, s, std::chrono::milliseconds(timeout_ms))) {
      return HAPTIC_TIMEOUT;
    }
    copy_state(s, out);
    return HAPTIC_OK;
  });
}

int haptic_client_step(haptic_client* client, uint32_t ticks, uint64_t* last_tick, haptic_error* err) {
  if (client == nullptr) return invalid(err, "Step: client: is NULL");
  return guarded(err, [&] {
    const std::uint64_t last = client->client.step(ticks);
    if (last_tick != nullptr) *last_tick = last;
    return HAPTIC_OK;
  });
}

void haptic_wall_spec_init(haptic_wall_spec* spec) {
  if (spec == nullptr) return;
  const haptic::WallSpec d;
  *spec = haptic_wall_spec{};
  spec->size = sizeof(haptic_wall_spec);
  spec->point = to_c(d.point);
  spec->normal = to_c(d.normal);
  spec->stiffness = d.impedance.stiffness;
  spec->damping = d.impedance.damping;
  spec->static_friction = d.impedance.static_friction;
  spec->dynamic_friction = d.impedance.dynamic_friction;
  spec->shared = d.shared ? 1 : 0;
}

int haptic_client_add_wall(haptic_client* client, const haptic_wall_spec* spec, haptic_object** out,
                           haptic_error* err) {
  if (out == nullptr) return invalid(err, "CreateObject: out: is NULL");
  *out = nullptr;
  if (client == nullptr) return invalid(err, "CreateObject: client: is NULL");
  if (spec == nullptr || spec->size < sizeof(haptic_wall_spec)) {
    return invalid(err, "CreateObject: object.wall: NULL or size smaller than version 1's haptic_wall_spec");
  }
  return guarded(err, [&] {
    haptic::WallSpec w;
    w.point = from_c(spec->point);
    w.normal = from_c(spec->normal);
    w.impedance.stiffness = spec->stiffness;
    w.impedance.damping = spec->damping;
    w.impedance.static_friction = spec->static_friction;
    w.impedance.dynamic_friction = spec->dynamic_friction;
    w.shared = spec->shared != 0;
    *out = new haptic_object{client->client.add_wall(w)};
    return HAPTIC_OK;
  });
}

int haptic_object_remove(haptic_object* object, haptic_error* err) {
  if (object == nullptr) {
    set_error(err, HAPTIC_OK, "");
    return HAPTIC_OK;
  }
  const int status = guarded(err, [&] {
    object->handle.remove();
    return HAPTIC_OK;
  });
  try {
    delete object;
  } catch (...) {
  }
  return status;
}

int haptic_client_set_operator_push(haptic_client* client, haptic_vec3 force, haptic_error* err) {
  if (client == nullptr) return invalid(err, "SetOperator: client: is NULL");
  return guarded(err, [&] {
    client->client.set_operator(haptic::OperatorInput::push(from_c(force)));
    return HAPTIC_OK;
  });
}

}  // extern "C"
