// The C API (haptic/haptic_c.h): each spec kind's init, objects and fields (add, update,
// remove, release), and scenes (applied and registered).
#include "c_api_internal.hpp"

using namespace haptic::c_api;  // this library's own helpers, for its C entry points

extern "C" {

// ---- specs ----

HAPTIC_C_INIT(haptic_wall_spec, spec_defaults<haptic_wall_spec>())
HAPTIC_C_INIT(haptic_sphere_spec, spec_defaults<haptic_sphere_spec>())
HAPTIC_C_INIT(haptic_box_spec, spec_defaults<haptic_box_spec>())
HAPTIC_C_INIT(haptic_capsule_spec, spec_defaults<haptic_capsule_spec>())
HAPTIC_C_INIT(haptic_tangent_plane_spec, spec_defaults<haptic_tangent_plane_spec>())
HAPTIC_C_INIT(haptic_mesh_spec, spec_defaults<haptic_mesh_spec>())
HAPTIC_C_INIT(haptic_spring_field_spec, spec_defaults<haptic_spring_field_spec>())
HAPTIC_C_INIT(haptic_distance_spring_spec, spec_defaults<haptic_distance_spring_spec>())
HAPTIC_C_INIT(haptic_potential_field_spec, spec_defaults<haptic_potential_field_spec>())
HAPTIC_C_INIT(haptic_linear_field_spec, spec_defaults<haptic_linear_field_spec>())
HAPTIC_C_INIT(haptic_viscous_field_spec, spec_defaults<haptic_viscous_field_spec>())
HAPTIC_C_INIT(haptic_detent_field_spec, spec_defaults<haptic_detent_field_spec>())
HAPTIC_C_INIT(haptic_orientation_spring_spec, spec_defaults<haptic_orientation_spring_spec>())
HAPTIC_C_INIT(haptic_orientation_detent_spec, spec_defaults<haptic_orientation_detent_spec>())

#define HAPTIC_C_ADD_OBJECT(NAME, CSPEC)                                                        \
  int haptic_client_add_##NAME(haptic_client* client, const CSPEC* spec, haptic_object** out,  \
                               haptic_error* err) {                                            \
    return add_object(client, spec, out, err);                                                 \
  }                                                                                            \
  int haptic_object_update_##NAME(haptic_object* object, const CSPEC* spec, haptic_error* err) { \
    return update_item(object, spec, "UpdateObject", err);                                     \
  }
HAPTIC_C_ADD_OBJECT(wall, haptic_wall_spec)
HAPTIC_C_ADD_OBJECT(sphere, haptic_sphere_spec)
HAPTIC_C_ADD_OBJECT(box, haptic_box_spec)
HAPTIC_C_ADD_OBJECT(capsule, haptic_capsule_spec)
HAPTIC_C_ADD_OBJECT(tangent_plane, haptic_tangent_plane_spec)
HAPTIC_C_ADD_OBJECT(mesh, haptic_mesh_spec)
#undef HAPTIC_C_ADD_OBJECT

#define HAPTIC_C_ADD_FIELD(NAME, CSPEC)                                                         \
  int haptic_client_add_##NAME(haptic_client* client, const CSPEC* spec, haptic_field** out,   \
                               haptic_error* err) {                                            \
    return add_field(client, spec, out, err);                                                  \
  }                                                                                            \
  int haptic_field_update_##NAME(haptic_field* field, const CSPEC* spec, haptic_error* err) {  \
    return update_item(field, spec, "UpdateField", err);                                       \
  }
HAPTIC_C_ADD_FIELD(spring_field, haptic_spring_field_spec)
HAPTIC_C_ADD_FIELD(distance_spring, haptic_distance_spring_spec)
HAPTIC_C_ADD_FIELD(potential_field, haptic_potential_field_spec)
HAPTIC_C_ADD_FIELD(linear_field, haptic_linear_field_spec)
HAPTIC_C_ADD_FIELD(viscous_field, haptic_viscous_field_spec)
HAPTIC_C_ADD_FIELD(detent_field, haptic_detent_field_spec)
HAPTIC_C_ADD_FIELD(orientation_spring, haptic_orientation_spring_spec)
HAPTIC_C_ADD_FIELD(orientation_detent, haptic_orientation_detent_spec)
#undef HAPTIC_C_ADD_FIELD

uint64_t haptic_object_id(const haptic_object* object) {
  return object != nullptr ? object->handle.id() : 0;
}
uint64_t haptic_field_id(const haptic_field* field) { return field != nullptr ? field->handle.id() : 0; }

int haptic_object_remove(haptic_object* object, haptic_error* err) {
  const int status = guarded(err, [&] {
    if (object != nullptr) object->handle.remove();
    return HAPTIC_OK;
  });
  delete object;  // the handle owns nothing any more, or its destructor swallows the error
  return status;
}

int haptic_field_remove(haptic_field* field, haptic_error* err) {
  const int status = guarded(err, [&] {
    if (field != nullptr) field->handle.remove();
    return HAPTIC_OK;
  });
  delete field;
  return status;
}

uint64_t haptic_object_release(haptic_object* object) {
  if (object == nullptr) return 0;
  const std::uint64_t id = object->handle.release();
  delete object;
  return id;
}

uint64_t haptic_field_release(haptic_field* field) {
  if (field == nullptr) return 0;
  const std::uint64_t id = field->handle.release();
  delete field;
  return id;
}

int haptic_object_stability(const haptic_object* object, haptic_stability_report* out,
                            haptic_error* err) {
  return guarded(err, [&] {
    require(object, "stability", "object");
    copy_report(object->handle.stability(), *SizedOut<haptic_stability_report>(out, "stability", "out"));
    return HAPTIC_OK;
  });
}

int haptic_field_stability(const haptic_field* field, haptic_stability_report* out,
                           haptic_error* err) {
  return guarded(err, [&] {
    require(field, "stability", "field");
    SizedOut<haptic_stability_report> written(out, "stability", "out");
    auto& c = *written;
    if (field->handle.stability()) {
      copy_report(*field->handle.stability(), c);
    } else {
      const std::uint32_t size = c.size;
      c = haptic_stability_report{};
      c.size = size;
    }
    return HAPTIC_OK;
  });
}

// ---- scenes ----

int haptic_client_apply_scene(haptic_client* client, const haptic_scene_item* items, uint32_t count,
                              haptic_applied_scene** out, haptic_error* err) {
  return guarded(err, [&] {
    require(out, "ApplyScene", "out");
    *out = nullptr;
    require(client, "ApplyScene", "client");
    haptic::AppliedScene applied = client->client.apply_scene(scene_of(items, count, "ApplyScene"));
    *out = applied_of(std::move(applied), client->client.last_scene_stability());
    return HAPTIC_OK;
  });
}

int haptic_client_apply_scene_file(haptic_client* client, const char* path,
                                   haptic_applied_scene** out, haptic_error* err) {
  return guarded(err, [&] {
    require(out, "apply_scene_file", "out");
    *out = nullptr;
    require(client, "apply_scene_file", "client");
    require(path, "apply_scene_file", "path");
    haptic::AppliedScene applied = client->client.apply_scene_file(path);
    *out = applied_of(std::move(applied), client->client.last_scene_stability());
    return HAPTIC_OK;
  });
}

void haptic_applied_scene_counts(const haptic_applied_scene* scene, uint32_t* objects,
                                 uint32_t* fields) {
  if (objects != nullptr) *objects = scene ? static_cast<uint32_t>(scene->objects.size()) : 0;
  if (fields != nullptr) *fields = scene ? static_cast<uint32_t>(scene->fields.size()) : 0;
}

haptic_object* haptic_applied_scene_take_object(haptic_applied_scene* scene, uint32_t index) {
  if (scene == nullptr || index >= scene->objects.size() || !scene->objects[index]) return nullptr;
  try {
    auto* object = new haptic_object{std::move(*scene->objects[index])};
    scene->objects[index].reset();
    return object;
  } catch (...) {
    return nullptr;
  }
}

haptic_field* haptic_applied_scene_take_field(haptic_applied_scene* scene, uint32_t index) {
  if (scene == nullptr || index >= scene->fields.size() || !scene->fields[index]) return nullptr;
  try {
    auto* field = new haptic_field{std::move(*scene->fields[index])};
    scene->fields[index].reset();
    return field;
  } catch (...) {
    return nullptr;
  }
}

int haptic_applied_scene_stability(const haptic_applied_scene* scene, uint32_t index,
                                   haptic_stability_report* out, haptic_error* err) {
  return guarded(err, [&] {
    require(scene, "last_scene_stability", "scene");
    if (index >= scene->stability.size()) {
      throw InvalidArgumentError("last_scene_stability: index: " + std::to_string(index) +
                                 " is past the scene's " + std::to_string(scene->stability.size()) +
                                 " objects");
    }
    copy_report(scene->stability[index],
                *SizedOut<haptic_stability_report>(out, "last_scene_stability", "out"));
    return HAPTIC_OK;
  });
}

void haptic_applied_scene_free(haptic_applied_scene* scene) {
  if (scene == nullptr) return;
  // Handles not taken let go of their items rather than removing them (haptic_c.h).
  for (auto& o : scene->objects) {
    if (o) o->release();
  }
  for (auto& f : scene->fields) {
    if (f) f->release();
  }
  delete scene;
}

int haptic_scene_json(const haptic_scene_item* items, uint32_t count, char* buffer, size_t capacity,
                      size_t* length, haptic_error* err) {
  return guarded(err, [&] {
    require(length, "scene_json", "length");
    if (capacity > 0) require(buffer, "scene_json", "buffer");
    const std::string json = haptic::scene_json(scene_of(items, count, "scene_json"));
    *length = json.size();
    if (capacity > 0) copy_text(buffer, capacity, json);
    return HAPTIC_OK;
  });
}

int haptic_client_scene(haptic_client* client, int32_t all_sessions, haptic_registered_scene** out,
                        haptic_error* err) {
  return guarded(err, [&] {
    require(out, "GetScene", "out");
    *out = nullptr;
    require(client, "GetScene", "client");
    *out = new haptic_registered_scene{client->client.scene(all_sessions != 0)};
    return HAPTIC_OK;
  });
}

void haptic_registered_scene_counts(const haptic_registered_scene* scene, uint32_t* objects,
                                    uint32_t* fields) {
  if (objects != nullptr) *objects = scene ? static_cast<uint32_t>(scene->scene.scene.objects.size()) : 0;
  if (fields != nullptr) *fields = scene ? static_cast<uint32_t>(scene->scene.scene.fields.size()) : 0;
}

int haptic_registered_scene_object(const haptic_registered_scene* scene, uint32_t index,
                                   haptic_scene_entry* out, haptic_error* err) {
  return guarded(err, [&] {
    require(scene, "scene.objects", "scene");
    check_index(scene->scene.scene.objects, index, "scene.objects");
    SizedOut<haptic_scene_entry> written(out, "scene.objects", "out");
    auto& c = *written;
    c.kind = kind_of(scene->scene.scene.objects[index]);
    c.id = scene->scene.object_ids[index];
    c.session_id = scene->scene.object_sessions[index];
    return HAPTIC_OK;
  });
}

int haptic_registered_scene_field(const haptic_registered_scene* scene, uint32_t index,
                                  haptic_scene_entry* out, haptic_error* err) {
  return guarded(err, [&] {
    require(scene, "scene.fields", "scene");
    check_index(scene->scene.scene.fields, index, "scene.fields");
    SizedOut<haptic_scene_entry> written(out, "scene.fields", "out");
    auto& c = *written;
    c.kind = kind_of(scene->scene.scene.fields[index]);
    c.id = scene->scene.field_ids[index];
    c.session_id = scene->scene.field_sessions[index];
    return HAPTIC_OK;
  });
}

int haptic_registered_scene_object_spec(const haptic_registered_scene* scene, uint32_t index,
                                        void* spec, haptic_error* err) {
  return guarded(err, [&] {
    require(scene, "scene.objects", "scene");
    check_index(scene->scene.scene.objects, index, "scene.objects");
    copy_spec(scene->scene.scene.objects[index], spec, "scene.objects");
    return HAPTIC_OK;
  });
}

int haptic_registered_scene_field_spec(const haptic_registered_scene* scene, uint32_t index,
                                       void* spec, haptic_error* err) {
  return guarded(err, [&] {
    require(scene, "scene.fields", "scene");
    check_index(scene->scene.scene.fields, index, "scene.fields");
    copy_spec(scene->scene.scene.fields[index], spec, "scene.fields");
    return HAPTIC_OK;
  });
}

void haptic_registered_scene_free(haptic_registered_scene* scene) { delete scene; }

int haptic_client_scene_energy(haptic_client* client, haptic_item_energy* out, uint32_t capacity,
                               uint32_t* count, haptic_error* err) {
  return guarded(err, [&] {
    require(client, "GetSceneEnergy", "client");
    copy_list(client->client.scene_energy(), out, capacity, count, "GetSceneEnergy",
              [](const haptic::ItemEnergy& e) {
                return haptic_item_energy{e.id, e.session_id, e.is_object, e.given_to_device,
                                          e.absorbed_from_device};
              });
    return HAPTIC_OK;
  });
}

int haptic_client_object_states(haptic_client* client, haptic_object_state* out, uint32_t capacity,
                                uint32_t* count, haptic_error* err) {
  return guarded(err, [&] {
    require(client, "GetObjectStates", "client");
    copy_list(client->client.object_states(), out, capacity, count, "GetObjectStates",
              [](const haptic::ObjectState& s) {
                return haptic_object_state{s.id, to_c(s.position), to_c(s.velocity)};
              });
    return HAPTIC_OK;
  });
}


}  // extern "C"
