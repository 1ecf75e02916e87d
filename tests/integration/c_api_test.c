/* The C API from C99 against a real lockstep hapticd (address from c_api_test_main.cpp): a wall
 * holds the operator's push; every object and field kind registers, reads back as given and
 * updates; a scene applies whole or not at all; refusals name the field; callbacks arrive on the
 * SDK's threads with the user's pointer; events, stats and sessions are read. */
#include "integration/c_api_test.h"

#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "haptic/haptic_c.h"

static int failures = 0;

#define CHECK(cond)                                                                 \
  do {                                                                              \
    if (!(cond)) {                                                                  \
      fprintf(stderr, "%s:%d: check failed: %s\n", __FILE__, __LINE__, #cond);     \
      failures++;                                                                   \
    }                                                                               \
  } while (0)

/* A call that must succeed: on failure, prints its message. */
#define OK(call)                                                                    \
  do {                                                                              \
    haptic_error ok_err_;                                                           \
    (void)ok_err_;                                                                  \
    if ((call) != HAPTIC_OK) {                                                      \
      fprintf(stderr, "%s:%d: %s failed\n", __FILE__, __LINE__, #call);            \
      failures++;                                                                   \
    }                                                                               \
  } while (0)

/* What the callbacks saw, guarded by `lock`: they run on the SDK's threads. */
typedef struct observed {
  pthread_mutex_t lock;
  pthread_t caller;
  int states;
  int states_on_caller_thread;
  uint64_t last_tick;
  int events;
  int event_kinds[64];
  uint64_t event_items[64];
} observed;

static void on_state(const haptic_state* state, void* user_data) {
  observed* seen = (observed*)user_data;
  pthread_mutex_lock(&seen->lock);
  seen->states++;
  if (pthread_equal(pthread_self(), seen->caller)) seen->states_on_caller_thread++;
  seen->last_tick = state->tick;
  pthread_mutex_unlock(&seen->lock);
}

static void on_event(const haptic_event* event, void* user_data) {
  observed* seen = (observed*)user_data;
  pthread_mutex_lock(&seen->lock);
  if (seen->events < 64) {
    seen->event_kinds[seen->events] = event->kind;
    seen->event_items[seen->events] = event->item_id;
  }
  seen->events++;
  pthread_mutex_unlock(&seen->lock);
}

static int step_and_get(haptic_client* client, uint32_t ticks, haptic_state* out) {
  haptic_error err;
  uint64_t last = 0;
  if (haptic_client_step(client, ticks, &last, &err) != HAPTIC_OK) {
    fprintf(stderr, "step: %s\n", err.message);
    return -1;
  }
  out->size = sizeof(*out);
  if (haptic_client_wait_for_tick(client, last, out, 5000, &err) != HAPTIC_OK) {
    fprintf(stderr, "wait_for_tick: %d %s\n", err.code, err.message);
    return -1;
  }
  return out->tick == last ? 0 : -1;
}

/* The scene file JSON of one item: equal JSON, equal specs (mesh arrays included). */
static char* json_of(int32_t kind, const void* spec) {
  haptic_scene_item item;
  size_t length = 0;
  char* json;
  item.kind = kind;
  item.spec = spec;
  if (haptic_scene_json(&item, 1, NULL, 0, &length, NULL) != HAPTIC_OK) return NULL;
  json = (char*)malloc(length + 1);
  if (json != NULL && haptic_scene_json(&item, 1, json, length + 1, &length, NULL) != HAPTIC_OK) {
    free(json);
    return NULL;
  }
  return json;
}

/* Every object and field kind, as the Python SDK's test registers them. */
typedef struct every_kind {
  haptic_wall_spec wall;
  haptic_sphere_spec sphere;
  haptic_box_spec box;
  haptic_capsule_spec capsule;
  haptic_tangent_plane_spec plane;
  haptic_mesh_spec mesh;
  haptic_spring_field_spec spring;
  haptic_distance_spring_spec distance_spring;
  haptic_potential_field_spec potential;
  haptic_linear_field_spec linear;
  haptic_viscous_field_spec viscous;
  haptic_detent_field_spec detent;
  haptic_orientation_spring_spec orientation_spring;
  haptic_orientation_detent_spec orientation_detent;
  haptic_scene_item items[14];
} every_kind;

static const haptic_vec3 kTetrahedron[4] = {{0, 0, 0}, {0.05, 0, 0}, {0, 0.05, 0}, {0, 0, 0.05}};
static const uint32_t kTetrahedronIndices[12] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};

static void make_every_kind(every_kind* k) {
  haptic_impedance stiff;
  haptic_pose pose;
  haptic_wall_spec_init(&k->wall);
  stiff = k->wall.impedance;
  stiff.stiffness = 1000.0;
  stiff.damping = 1.0;
  pose = (haptic_pose){{0.3, 0.3, 0.3}, {1, 0, 0, 0}};
  k->wall.point.z = -0.05;
  k->wall.impedance = stiff;
  haptic_sphere_spec_init(&k->sphere);
  k->sphere.center.x = 0.2;
  k->sphere.radius = 0.01;
  k->sphere.impedance = stiff;
  haptic_box_spec_init(&k->box);
  k->box.pose = pose;
  k->box.half_extents = (haptic_vec3){0.01, 0.02, 0.03};
  k->box.impedance = stiff;
  haptic_capsule_spec_init(&k->capsule);
  k->capsule.pose = pose;
  k->capsule.radius = 0.01;
  k->capsule.half_length = 0.02;
  k->capsule.impedance = stiff;
  haptic_tangent_plane_spec_init(&k->plane);
  k->plane.pose = pose;
  k->plane.normal = (haptic_vec3){0, 1, 0};
  k->plane.tangential_stiffness = 50.0;
  k->plane.impedance = stiff;
  haptic_mesh_spec_init(&k->mesh);
  k->mesh.pose = pose;
  k->mesh.vertices = kTetrahedron;
  k->mesh.vertex_count = 4;
  k->mesh.indices = kTetrahedronIndices;
  k->mesh.index_count = 12;
  k->mesh.impedance = stiff;

  haptic_spring_field_spec_init(&k->spring);
  k->spring.anchor.z = 0.02;
  k->spring.stiffness = 20.0;
  k->spring.max_force = 2.0;
  haptic_distance_spring_spec_init(&k->distance_spring);
  k->distance_spring.anchor.kind = HAPTIC_DISTANCE_LINE;
  k->distance_spring.anchor.axis = (haptic_vec3){1, 0, 0};
  k->distance_spring.stiffness = 10.0;
  haptic_potential_field_spec_init(&k->potential);
  k->potential.distance.origin.x = 0.5;
  k->potential.gain = 10.0;
  k->potential.offset = 0.01;
  haptic_linear_field_spec_init(&k->linear);
  k->linear.origin = (haptic_vec3){0.5, 0.5, 0};
  k->linear.force.z = 0.1;
  k->linear.radius = 0.01;
  k->linear.fade_width = 0.005;
  haptic_viscous_field_spec_init(&k->viscous);
  k->viscous.damping = 0.5;
  k->viscous.center = (haptic_vec3){0.5, 0.5, 0.5};
  k->viscous.radius = 0.01;
  k->viscous.fade_width = 0.005;
  haptic_detent_field_spec_init(&k->detent);
  k->detent.distance.origin.x = -0.5;
  k->detent.depth = 0.01;
  k->detent.radius = 0.01;
  k->detent.rim_height = 0.001;
  k->detent.rim_width = 0.005;
  haptic_orientation_spring_spec_init(&k->orientation_spring);
  k->orientation_spring.target = (haptic_quaternion){0.5, 0.5, -0.5, 0.5};
  k->orientation_spring.stiffness = 0.5;
  k->orientation_spring.damping = 0.01;
  k->orientation_spring.max_torque = 0.1;
  k->orientation_spring.law = HAPTIC_LAW_BACKWARD_DIFFERENCE;
  haptic_orientation_detent_spec_init(&k->orientation_detent);
  k->orientation_detent.target = (haptic_quaternion){0, 0, 0, 1};
  k->orientation_detent.depth = 0.01;
  k->orientation_detent.radius = 0.2;
  k->orientation_detent.rim_height = 0.002;
  k->orientation_detent.rim_width = 0.1;
  k->orientation_detent.damping = 0.001;

  k->items[0] = (haptic_scene_item){HAPTIC_KIND_WALL, &k->wall};
  k->items[1] = (haptic_scene_item){HAPTIC_KIND_SPHERE, &k->sphere};
  k->items[2] = (haptic_scene_item){HAPTIC_KIND_BOX, &k->box};
  k->items[3] = (haptic_scene_item){HAPTIC_KIND_CAPSULE, &k->capsule};
  k->items[4] = (haptic_scene_item){HAPTIC_KIND_TANGENT_PLANE, &k->plane};
  k->items[5] = (haptic_scene_item){HAPTIC_KIND_MESH, &k->mesh};
  k->items[6] = (haptic_scene_item){HAPTIC_KIND_SPRING_FIELD, &k->spring};
  k->items[7] = (haptic_scene_item){HAPTIC_KIND_DISTANCE_SPRING, &k->distance_spring};
  k->items[8] = (haptic_scene_item){HAPTIC_KIND_POTENTIAL_FIELD, &k->potential};
  k->items[9] = (haptic_scene_item){HAPTIC_KIND_LINEAR_FIELD, &k->linear};
  k->items[10] = (haptic_scene_item){HAPTIC_KIND_VISCOUS_FIELD, &k->viscous};
  k->items[11] = (haptic_scene_item){HAPTIC_KIND_DETENT_FIELD, &k->detent};
  k->items[12] = (haptic_scene_item){HAPTIC_KIND_ORIENTATION_SPRING, &k->orientation_spring};
  k->items[13] = (haptic_scene_item){HAPTIC_KIND_ORIENTATION_DETENT, &k->orientation_detent};
}

/* Room for any spec read back: the largest of them, aligned for doubles. */
typedef union any_spec {
  uint32_t size;
  haptic_wall_spec wall;
  haptic_sphere_spec sphere;
  haptic_box_spec box;
  haptic_capsule_spec capsule;
  haptic_tangent_plane_spec plane;
  haptic_mesh_spec mesh;
  haptic_spring_field_spec spring;
  haptic_distance_spring_spec distance_spring;
  haptic_potential_field_spec potential;
  haptic_linear_field_spec linear;
  haptic_viscous_field_spec viscous;
  haptic_detent_field_spec detent;
  haptic_orientation_spring_spec orientation_spring;
  haptic_orientation_detent_spec orientation_detent;
} any_spec;

/* The read-back scene holds exactly `expected` (objects first), with the handles' ids. */
static void check_scene_holds(haptic_client* client, const haptic_scene_item* expected,
                              uint32_t count, const uint64_t* ids) {
  haptic_registered_scene* scene = NULL;
  haptic_error err;
  uint32_t objects = 0, fields = 0, i;
  OK(haptic_client_scene(client, 0, &scene, &err));
  if (scene == NULL) return;
  haptic_registered_scene_counts(scene, &objects, &fields);
  CHECK(objects + fields == count);
  for (i = 0; i < objects + fields && i < count; ++i) {
    haptic_scene_entry entry;
    any_spec spec;
    char *given, *held;
    const int is_object = i < objects;
    const uint32_t index = is_object ? i : i - objects;
    entry.size = sizeof(entry);
    memset(&spec, 0, sizeof(spec));
    spec.size = sizeof(spec);
    OK(is_object ? haptic_registered_scene_object(scene, index, &entry, &err)
                 : haptic_registered_scene_field(scene, index, &entry, &err));
    CHECK(entry.kind == expected[i].kind);
    CHECK(entry.id == ids[i] && entry.session_id == haptic_client_session_id(client));
    OK(is_object ? haptic_registered_scene_object_spec(scene, index, &spec, &err)
                 : haptic_registered_scene_field_spec(scene, index, &spec, &err));
    given = json_of(expected[i].kind, expected[i].spec);
    held = json_of(entry.kind, &spec);
    CHECK(given != NULL && held != NULL && strcmp(given, held) == 0);
    if (given != NULL && held != NULL && strcmp(given, held) != 0) {
      fprintf(stderr, "item %u given %s\n  held %s\n", i, given, held);
    }
    free(given);
    free(held);
  }
  {
    /* Reading past the end, or into a struct of another kind, is refused naming the field. */
    haptic_scene_entry entry;
    haptic_sphere_spec too_small;
    entry.size = sizeof(entry);
    CHECK(haptic_registered_scene_object(scene, objects, &entry, &err) == HAPTIC_ERROR_INVALID_ARGUMENT);
    CHECK(strstr(err.message, "scene.objects: index") != NULL);
    if (objects > 0 && expected[0].kind == HAPTIC_KIND_WALL) {
      memset(&too_small, 0, sizeof(too_small));
      too_small.size = 8;
      CHECK(haptic_registered_scene_object_spec(scene, 0, &too_small, &err) == HAPTIC_ERROR_INVALID_ARGUMENT);
      CHECK(strstr(err.message, "object.wall: size 8") != NULL);
    }
  }
  haptic_registered_scene_free(scene);
}

static void test_wall_holds_a_push(haptic_client* client) {
  haptic_error err;
  haptic_wall_spec wall;
  haptic_object* object = NULL;
  haptic_object* refused = NULL;
  haptic_stability_report report;
  haptic_state s;
  haptic_vec3 push = {0.0, 0.0, -5.0};

  /* The horizontal wall through the origin; the operator pushes 5 N down into it. */
  haptic_wall_spec_init(&wall);
  CHECK(wall.size == sizeof(wall) && wall.normal.z == 1.0 && wall.impedance.law == HAPTIC_LAW_VELOCITY);
  wall.impedance.stiffness = 1000.0;
  wall.impedance.damping = 1.0;
  CHECK(haptic_client_add_wall(client, &wall, &object, &err) == HAPTIC_OK);
  CHECK(object != NULL && haptic_object_id(object) > 0);
  report.size = sizeof(report);
  OK(haptic_object_stability(object, &report, &err));
  CHECK(report.available == 1 && report.device_known == 1 && report.colgate_min_damping > 0.0);
  CHECK(haptic_client_set_operator_push(client, push, &err) == HAPTIC_OK);
  CHECK(step_and_get(client, 3000, &s) == 0);
  /* At rest the wall balances the push: 5 mm deep, 5 N up. */
  CHECK(s.contact_count == 1u);
  CHECK(fabs(s.position.z + 0.005) < 1e-6);
  CHECK(fabs(s.force.z - 5.0) < 1e-3);
  CHECK(fabs(s.force.x) < 1e-12 && fabs(s.force.y) < 1e-12);
  CHECK(s.received_at_ns > 0 && s.has_orientation == 0);

  /* Updated to half the stiffness, it holds the push twice as deep. */
  wall.impedance.stiffness = 500.0;
  OK(haptic_object_update_wall(object, &wall, &err));
  CHECK(step_and_get(client, 3000, &s) == 0);
  CHECK(fabs(s.position.z + 0.010) < 1e-6);

  /* A refused update names the field and leaves the wall as it was. */
  wall.impedance.damping = -1.0;
  CHECK(haptic_object_update_wall(object, &wall, &err) == HAPTIC_ERROR_INVALID_ARGUMENT);
  CHECK(strstr(err.message, "impedance.damping") != NULL);
  CHECK(step_and_get(client, 10, &s) == 0);
  CHECK(fabs(s.position.z + 0.010) < 1e-6);

  /* Removed, the force ramps out and is zero after. */
  CHECK(haptic_object_remove(object, &err) == HAPTIC_OK);
  CHECK(step_and_get(client, 100, &s) == 0);
  CHECK(s.force.z == 0.0 && s.contact_count == 0u);

  /* A bad wall is refused naming the field, and makes nothing. */
  haptic_wall_spec_init(&wall);
  wall.normal.z = NAN;
  wall.impedance.stiffness = 1000.0;
  CHECK(haptic_client_add_wall(client, &wall, &refused, &err) == HAPTIC_ERROR_INVALID_ARGUMENT);
  CHECK(err.code == HAPTIC_ERROR_INVALID_ARGUMENT);
  CHECK(strncmp(err.message, "CreateObject: object.half_space.normal", 38) == 0);
  CHECK(refused == NULL);
  haptic_wall_spec_init(&wall);
  wall.impedance.stiffness = -1.0;
  CHECK(haptic_client_add_wall(client, &wall, &refused, &err) == HAPTIC_ERROR_INVALID_ARGUMENT);
  CHECK(strncmp(err.message, "CreateObject: object.impedance.stiffness: must be >= 0", 54) == 0);
  CHECK(refused == NULL);
  /* An enum out of range is refused by the library itself, naming the field. */
  haptic_wall_spec_init(&wall);
  wall.impedance.law = 9;
  CHECK(haptic_client_add_wall(client, &wall, &refused, &err) == HAPTIC_ERROR_INVALID_ARGUMENT);
  CHECK(strcmp(err.message, "CreateObject: object.wall.impedance.law: 9 is not one of 0..3") == 0);
  /* A struct from an older, smaller header is refused, as is NULL: codes, never a crash. */
  haptic_wall_spec_init(&wall);
  wall.size = 16;
  CHECK(haptic_client_add_wall(client, &wall, &refused, &err) == HAPTIC_ERROR_INVALID_ARGUMENT);
  CHECK(strstr(err.message, "object.wall: size 16 is smaller than version 1's") != NULL);
  CHECK(haptic_client_add_wall(client, NULL, &refused, &err) == HAPTIC_ERROR_INVALID_ARGUMENT);
  CHECK(strcmp(err.message, "CreateObject: object.wall: is NULL") == 0);
  /* A mesh whose arrays are NULL with counts above 0 is refused naming the array: never read. */
  {
    haptic_mesh_spec mesh;
    haptic_mesh_spec_init(&mesh);
    mesh.impedance.stiffness = 1000.0;
    mesh.vertices = NULL;
    mesh.vertex_count = 4;
    mesh.indices = kTetrahedronIndices;
    mesh.index_count = 12;
    CHECK(haptic_client_add_mesh(client, &mesh, &refused, &err) == HAPTIC_ERROR_INVALID_ARGUMENT);
    CHECK(strstr(err.message, "vertices: is NULL with vertex_count > 0") != NULL);
    CHECK(refused == NULL);
    mesh.vertices = kTetrahedron;
    mesh.indices = NULL;
    CHECK(haptic_client_add_mesh(client, &mesh, &refused, &err) == HAPTIC_ERROR_INVALID_ARGUMENT);
    CHECK(strstr(err.message, "indices: is NULL with index_count > 0") != NULL);
    CHECK(refused == NULL);
  }
  /* Nothing was made: the tool falls freely under the push. */
  CHECK(step_and_get(client, 10, &s) == 0);
  CHECK(s.contact_count == 0u && s.force.z == 0.0);
  {
    haptic_operator_input release;
    haptic_operator_input_init(&release);
    CHECK(release.mode == HAPTIC_OPERATOR_RELEASE && release.size == sizeof(release));
    OK(haptic_client_set_operator(client, &release, &err));
    release.profile_shape = 17;
    CHECK(haptic_client_set_operator(client, &release, &err) == HAPTIC_ERROR_INVALID_ARGUMENT);
    CHECK(strcmp(err.message, "SetOperator: input.profile_shape: 17 is not one of 0..4") == 0);
  }
}

static void test_every_kind_registers_reads_back_and_updates(haptic_client* client) {
  every_kind k;
  haptic_object* objects[6] = {NULL};
  haptic_field* fields[8] = {NULL};
  uint64_t ids[14];
  haptic_error err;
  haptic_stability_report report;
  int i;
  make_every_kind(&k);
  OK(haptic_client_add_wall(client, &k.wall, &objects[0], &err));
  OK(haptic_client_add_sphere(client, &k.sphere, &objects[1], &err));
  OK(haptic_client_add_box(client, &k.box, &objects[2], &err));
  OK(haptic_client_add_capsule(client, &k.capsule, &objects[3], &err));
  OK(haptic_client_add_tangent_plane(client, &k.plane, &objects[4], &err));
  OK(haptic_client_add_mesh(client, &k.mesh, &objects[5], &err));
  OK(haptic_client_add_spring_field(client, &k.spring, &fields[0], &err));
  OK(haptic_client_add_distance_spring(client, &k.distance_spring, &fields[1], &err));
  OK(haptic_client_add_potential_field(client, &k.potential, &fields[2], &err));
  OK(haptic_client_add_linear_field(client, &k.linear, &fields[3], &err));
  OK(haptic_client_add_viscous_field(client, &k.viscous, &fields[4], &err));
  OK(haptic_client_add_detent_field(client, &k.detent, &fields[5], &err));
  OK(haptic_client_add_orientation_spring(client, &k.orientation_spring, &fields[6], &err));
  OK(haptic_client_add_orientation_detent(client, &k.orientation_detent, &fields[7], &err));
  for (i = 0; i < 6; ++i) ids[i] = haptic_object_id(objects[i]);
  for (i = 0; i < 8; ++i) ids[6 + i] = haptic_field_id(fields[i]);
  check_scene_holds(client, k.items, 14, ids);
  report.size = sizeof(report);
  OK(haptic_field_stability(fields[6], &report, &err));
  CHECK(report.available == 1);  /* an orientation spring's, on the handle */
  OK(haptic_field_stability(fields[0], &report, &err));
  CHECK(report.available == 0);

  /* Updates, one of them to another kind: a detent becomes an orientation spring. */
  k.sphere.radius = 0.03;
  OK(haptic_object_update_sphere(objects[1], &k.sphere, &err));
  k.viscous.damping = 1.5;
  OK(haptic_field_update_viscous_field(fields[4], &k.viscous, &err));
  haptic_orientation_spring_spec_init(&k.orientation_spring);
  k.orientation_spring.stiffness = 0.2;
  OK(haptic_field_update_orientation_spring(fields[7], &k.orientation_spring, &err));
  k.items[13] = (haptic_scene_item){HAPTIC_KIND_ORIENTATION_SPRING, &k.orientation_spring};
  {
    haptic_orientation_spring_spec first;
    haptic_orientation_spring_spec_init(&first);
    first.target = (haptic_quaternion){0.5, 0.5, -0.5, 0.5};
    first.stiffness = 0.5;
    first.damping = 0.01;
    first.max_torque = 0.1;
    first.law = HAPTIC_LAW_BACKWARD_DIFFERENCE;
    k.items[12].spec = &first;
    check_scene_holds(client, k.items, 14, ids);
  }
  /* A refused update names the field and changes nothing. */
  k.sphere.radius = -1.0;
  CHECK(haptic_object_update_sphere(objects[1], &k.sphere, &err) == HAPTIC_ERROR_INVALID_ARGUMENT);
  CHECK(strstr(err.message, "object.sphere.radius") != NULL);

  for (i = 0; i < 6; ++i) OK(haptic_object_remove(objects[i], &err));
  for (i = 0; i < 8; ++i) OK(haptic_field_remove(fields[i], &err));
  check_scene_holds(client, NULL, 0, NULL);
}

static void test_a_scene_applies_whole_or_not_at_all(haptic_client* client) {
  every_kind k;
  haptic_applied_scene* applied = NULL;
  haptic_error err;
  uint32_t objects = 0, fields = 0, i;
  uint64_t ids[14];
  haptic_object* taken[6] = {NULL};
  haptic_stability_report report;
  haptic_sphere_spec bad;
  haptic_scene_item with_bad[3];
  make_every_kind(&k);
  OK(haptic_client_apply_scene(client, k.items, 14, &applied, &err));
  haptic_applied_scene_counts(applied, &objects, &fields);
  CHECK(objects == 6 && fields == 8);
  for (i = 0; i < 6; ++i) {
    taken[i] = haptic_applied_scene_take_object(applied, i);
    CHECK(taken[i] != NULL);
    ids[i] = haptic_object_id(taken[i]);
  }
  CHECK(haptic_applied_scene_take_object(applied, 0) == NULL);  /* taken already */
  for (i = 0; i < 8; ++i) {
    haptic_field* field = haptic_applied_scene_take_field(applied, i);
    ids[6 + i] = haptic_field_id(field);
    haptic_field_release(field);
  }
  report.size = sizeof(report);
  OK(haptic_applied_scene_stability(applied, 1, &report, &err));
  CHECK(report.available == 1 && report.device_known == 1);
  CHECK(haptic_applied_scene_stability(applied, 6, &report, &err) == HAPTIC_ERROR_INVALID_ARGUMENT);
  haptic_applied_scene_free(applied);
  check_scene_holds(client, k.items, 14, ids);

  /* A scene with one bad sphere is refused naming it; the scene before stays whole. */
  haptic_sphere_spec_init(&bad);
  bad.radius = -0.5;
  with_bad[0] = k.items[0];
  with_bad[1] = (haptic_scene_item){HAPTIC_KIND_SPHERE, &bad};
  with_bad[2] = k.items[6];
  applied = NULL;
  CHECK(haptic_client_apply_scene(client, with_bad, 3, &applied, &err) == HAPTIC_ERROR_INVALID_ARGUMENT);
  CHECK(applied == NULL);
  CHECK(strstr(err.message, "scene.objects[1]") != NULL);
  with_bad[1].kind = 42;
  CHECK(haptic_client_apply_scene(client, with_bad, 3, &applied, &err) == HAPTIC_ERROR_INVALID_ARGUMENT);
  CHECK(strcmp(err.message, "ApplyScene: kind: 42 is not a haptic_kind") == 0);
  check_scene_holds(client, k.items, 14, ids);

  /* An empty scene clears it; the handles of the earlier one are stale and free quietly. */
  OK(haptic_client_apply_scene(client, NULL, 0, &applied, &err));
  haptic_applied_scene_free(applied);
  check_scene_holds(client, NULL, 0, NULL);
  for (i = 0; i < 6; ++i) OK(haptic_object_remove(taken[i], &err));
}

static void test_lists_stats_and_admin_calls(haptic_client* client) {
  haptic_error err;
  haptic_stats stats;
  haptic_stream_stats streams[4];
  haptic_session_summary sessions[4];
  haptic_receive_counters counters;
  haptic_device_info info;
  uint32_t count = 0;
  char text[17];

  info.size = sizeof(info);
  OK(haptic_client_device_info(client, &info, &err));
  CHECK(info.simulated == 1 && info.loop_rate_hz > 0.0 && info.name[0] != '\0' && info.dof == 3u);
  CHECK(strcmp(info.model, "point_mass") == 0);
  CHECK(info.workspace_min.z < info.workspace_max.z);

  stats.size = sizeof(stats);
  OK(haptic_client_stats(client, &stats, streams, 4, NULL, 0, &err));
  CHECK(stats.ticks > 0 && stats.sessions == 1u && stats.client_count == 1u && stats.has_federation == 0);
  CHECK(streams[0].session_id == haptic_client_session_id(client));
  CHECK(strcmp(streams[0].client_name, "c-api-test") == 0);
  CHECK(haptic_client_stats(client, &stats, NULL, 3, NULL, 0, &err) == HAPTIC_ERROR_INVALID_ARGUMENT);
  CHECK(strcmp(err.message, "GetStats: clients: is NULL") == 0);

  OK(haptic_client_sessions(client, sessions, 4, &count, &err));
  CHECK(count == 1u && sessions[0].session_id == haptic_client_session_id(client));
  CHECK(sessions[0].role == HAPTIC_ROLE_NONE);
  OK(haptic_client_sessions(client, NULL, 0, &count, &err));  /* only how many */
  CHECK(count == 1u);
  haptic_session_id_text(haptic_client_session_id(client), text);
  CHECK(strlen(text) == 16);

  counters.size = sizeof(counters);
  OK(haptic_client_receive_counters(client, &counters, &err));
  CHECK(counters.accepted > 0 && counters.rejected == 0);
  CHECK(haptic_client_lease_timeout_ms(client) > 0);
  CHECK(haptic_client_connection_state(client) == HAPTIC_CONNECTION_CONNECTED);
  /* No recording_dir on this server: refused with the server's reason. */
  CHECK(haptic_client_start_recording(client, "x.rec", NULL, &err) == HAPTIC_ERROR_FAILED_PRECONDITION);
}

static void test_motion_between_samples(void) {
  /* A path with constant acceleration: prediction and interpolation are exact on it. */
  haptic_state a, b;
  haptic_vec3 p;
  memset(&a, 0, sizeof(a));
  memset(&b, 0, sizeof(b));
  a.server_time = 1.0;
  b.server_time = 1.001;
  a.velocity.x = 0.1;
  b.position.x = 0.1 * 0.001 + 0.5 * 2.0 * 0.001 * 0.001;
  b.velocity.x = 0.1 + 2.0 * 0.001;
  p = haptic_predict_position(&a, &b, 1.002);
  CHECK(fabs(p.x - (0.1 * 0.002 + 0.5 * 2.0 * 0.002 * 0.002)) < 1e-12);
  p = haptic_interpolate_position(&a, &b, 1.0005);
  CHECK(fabs(p.x - (0.1 * 0.0005 + 0.5 * 2.0 * 0.0005 * 0.0005)) < 1e-12);
}

int c_api_test_run(const char* address) {
  haptic_error err;
  haptic_client_config config;
  haptic_client* client = NULL;
  observed seen;
  haptic_state s;
  double server_time = 0.0;
  int i, saw_watch_started = 0, saw_created = 0, states;

  failures = 0;
  CHECK(haptic_c_version() == HAPTIC_C_VERSION);
  haptic_client_config_init(&config);
  CHECK(config.size == sizeof(config));
  CHECK(strcmp(config.server_address, "127.0.0.1:50051") == 0 && config.reconnect == 1);
  config.server_address = address;
  config.client_name = "c-api-test";
  config.heartbeat_period_ms = 20;
  if (haptic_client_open(&config, &client, &err) != HAPTIC_OK) {
    fprintf(stderr, "open: %d %s\n", err.code, err.message);
    return 1;
  }
  CHECK(err.code == HAPTIC_OK && err.message[0] == '\0');

  /* Callbacks: on the SDK's threads, with the pointer given. */
  memset(&seen, 0, sizeof(seen));
  pthread_mutex_init(&seen.lock, NULL);
  seen.caller = pthread_self();
  OK(haptic_client_on_state(client, on_state, &seen, &err));
  OK(haptic_client_on_event(client, on_event, &seen, &err));

  test_wall_holds_a_push(client);
  test_every_kind_registers_reads_back_and_updates(client);
  test_a_scene_applies_whole_or_not_at_all(client);
  test_lists_stats_and_admin_calls(client);
  test_motion_between_samples();

  /* The stream's datagrams reached the callback, never on this thread. */
  CHECK(step_and_get(client, 50, &s) == 0);
  for (i = 0; i < 200; ++i) {
    uint64_t last;
    pthread_mutex_lock(&seen.lock);
    last = seen.last_tick;
    pthread_mutex_unlock(&seen.lock);
    if (last >= s.tick) break;
    (void)haptic_client_poll_state(client, &s, 10, NULL);
  }
  OK(haptic_client_on_state(client, NULL, NULL, &err));
  OK(haptic_client_on_event(client, NULL, NULL, &err));
  pthread_mutex_lock(&seen.lock);
  states = seen.states;
  CHECK(seen.states > 0 && seen.states_on_caller_thread == 0);
  for (i = 0; i < seen.events && i < 64; ++i) {
    if (seen.event_kinds[i] == HAPTIC_EVENT_WATCH_STARTED) saw_watch_started = 1;
    if (seen.event_kinds[i] == HAPTIC_EVENT_SCENE_CHANGED && seen.event_items[i] != 0) saw_created = 1;
  }
  pthread_mutex_unlock(&seen.lock);
  CHECK(saw_watch_started && saw_created);
  /* Stopped: no more calls. */
  CHECK(step_and_get(client, 50, &s) == 0);
  (void)haptic_client_poll_state(client, &s, 50, NULL);
  pthread_mutex_lock(&seen.lock);
  CHECK(seen.states == states);
  pthread_mutex_unlock(&seen.lock);

  CHECK(haptic_client_server_time_at(client, haptic_steady_clock_ns(), &server_time) == 1);
  CHECK(server_time > 0.0);

  /* No exception crosses: a NULL argument is a code. */
  CHECK(haptic_client_step(NULL, 1, NULL, &err) == HAPTIC_ERROR_INVALID_ARGUMENT);
  CHECK(strcmp(err.message, "Step: client: is NULL") == 0);
  if (failures > 0) fprintf(stderr, "last error: %d %s\n", err.code, err.message);

  OK(haptic_client_close(client, &err));
  pthread_mutex_destroy(&seen.lock);
  return failures;
}

/* ---- the recorder ---- */

/* What the state callback saw, in the recorder's column layout (docs/recorder.md). */
typedef struct seen_samples {
  pthread_mutex_t lock;
  size_t count;
  haptic_state states[4096];
} seen_samples;

static void on_recorded_state(const haptic_state* state, void* user_data) {
  seen_samples* seen = (seen_samples*)user_data;
  pthread_mutex_lock(&seen->lock);
  if (seen->count < sizeof(seen->states) / sizeof(seen->states[0])) seen->states[seen->count++] = *state;
  pthread_mutex_unlock(&seen->lock);
}

static uint64_t last_seen_tick(seen_samples* seen) {
  uint64_t tick = 0;
  pthread_mutex_lock(&seen->lock);
  if (seen->count > 0) tick = seen->states[seen->count - 1].tick;
  pthread_mutex_unlock(&seen->lock);
  return tick;
}

/* The samples as a CSV with the recorder's column names, doubles to 17 digits. */
static int write_seen(const seen_samples* seen, const char* path) {
  size_t i;
  FILE* file = fopen(path, "w");
  if (file == NULL) return -1;
  fprintf(file, "received_ns,arrived_ns,tick,sequence,server_time_s,position_x_m,position_y_m,"
                "position_z_m,velocity_x_m_s,velocity_y_m_s,velocity_z_m_s,force_x_N,force_y_N,"
                "force_z_N,proxy_x_m,proxy_y_m,proxy_z_m,contact_count,flags,buttons,age_ns,"
                "orientation_w,orientation_x,orientation_y,orientation_z,torque_x_Nm,torque_y_Nm,"
                "torque_z_Nm\n");
  for (i = 0; i < seen->count; ++i) {
    const haptic_state* s = &seen->states[i];
    fprintf(file, "%lld,%lld,%llu,%llu,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,"
                  "%.17g,%.17g,%.17g,%u,%u,%u,%lld,",
            (long long)s->received_at_ns, s->arrived_at_ns != 0 ? (long long)s->arrived_at_ns : -1LL,
            (unsigned long long)s->tick, (unsigned long long)s->sequence, s->server_time, s->position.x,
            s->position.y, s->position.z, s->velocity.x, s->velocity.y, s->velocity.z, s->force.x,
            s->force.y, s->force.z, s->proxy.x, s->proxy.y, s->proxy.z, s->contact_count, s->flags,
            s->buttons, (long long)s->age_ns);
    if (s->has_orientation) {
      fprintf(file, "%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n", s->orientation.w, s->orientation.x,
              s->orientation.y, s->orientation.z, s->torque.x, s->torque.y, s->torque.z);
    } else {
      fprintf(file, "NaN,NaN,NaN,NaN,NaN,NaN,NaN\n");  /* as the recorder writes an absent one */
    }
  }
  return fclose(file) == 0 ? 0 : -1;
}

int c_api_record_run(const char* address, const char* dir) {
  static seen_samples seen;
  haptic_error err;
  haptic_client_config config;
  haptic_client* client = NULL;
  haptic_recorder_options options;
  haptic_recorder *csv = NULL, *hdf5 = NULL, *refused = NULL;
  haptic_recorder_stats csv_totals, hdf5_totals;
  haptic_receive_counters before, after;
  haptic_wall_spec wall;
  haptic_object* object = NULL;
  haptic_vec3 push = {0.0, 0.0, -2.0};
  char csv_path[512], hdf5_path[512], seen_path[512], txt_path[512];
  int chunk, i;

  failures = 0;
  memset(&seen, 0, sizeof(seen));
  pthread_mutex_init(&seen.lock, NULL);
  snprintf(csv_path, sizeof(csv_path), "%s/session.csv", dir);
  snprintf(hdf5_path, sizeof(hdf5_path), "%s/session.h5", dir);
  snprintf(seen_path, sizeof(seen_path), "%s/seen.csv", dir);
  snprintf(txt_path, sizeof(txt_path), "%s/session.txt", dir);

  haptic_client_config_init(&config);
  config.server_address = address;
  config.client_name = "c-recorder-test";
  if (haptic_client_open(&config, &client, &err) != HAPTIC_OK) {
    fprintf(stderr, "open: %s\n", err.message);
    return 1;
  }
  before.size = sizeof(before);
  after.size = sizeof(after);
  OK(haptic_client_receive_counters(client, &before, &err));

  haptic_recorder_options_init(&options);
  CHECK(options.size == sizeof(options) && options.queue_capacity == 65536u && options.events == 1);
  options.path = csv_path;
  OK(haptic_client_record(client, &options, &csv, &err));
  CHECK(csv != NULL && strcmp(haptic_recorder_path(csv), csv_path) == 0);
  CHECK(strstr(haptic_recorder_events_path(csv), "session.events.csv") != NULL);
  options.path = hdf5_path;
  OK(haptic_client_record(client, &options, &hdf5, &err));
  /* Refused, naming the field, and nothing made: an unknown extension, an existing file. */
  options.path = txt_path;
  CHECK(haptic_client_record(client, &options, &refused, &err) == HAPTIC_ERROR_INVALID_ARGUMENT);
  CHECK(refused == NULL && strncmp(err.message, "record: path: ", 14) == 0);
  options.path = csv_path;
  CHECK(haptic_client_record(client, &options, &refused, &err) == HAPTIC_ERROR_INVALID_ARGUMENT);
  CHECK(strstr(err.message, "exists") != NULL);
  options.path = hdf5_path;
  options.format = 7;
  CHECK(haptic_client_record(client, &options, &refused, &err) == HAPTIC_ERROR_INVALID_ARGUMENT);
  CHECK(strcmp(err.message, "record: options.format: 7 is not one of 0..2") == 0);

  /* The session: a wall, the hand pushing into it, the wall removed; the callback watching. */
  OK(haptic_client_on_state(client, on_recorded_state, &seen, &err));
  haptic_wall_spec_init(&wall);
  wall.impedance.stiffness = 1000.0;
  wall.impedance.damping = 1.0;
  OK(haptic_client_add_wall(client, &wall, &object, &err));
  OK(haptic_client_set_operator_push(client, push, &err));
  for (chunk = 0; chunk < 20; ++chunk) {
    uint64_t last = 0;
    haptic_state s;
    if (chunk == 15) OK(haptic_object_remove(object, &err));
    OK(haptic_client_step(client, 50, &last, &err));
    s.size = sizeof(s);
    for (i = 0; i < 1000 && last_seen_tick(&seen) < last; ++i) (void)haptic_client_poll_state(client, &s, 5, NULL);
    CHECK(last_seen_tick(&seen) == last);
  }
  OK(haptic_client_on_state(client, NULL, NULL, &err));
  OK(haptic_client_receive_counters(client, &after, &err));

  csv_totals.size = sizeof(csv_totals);
  hdf5_totals.size = sizeof(hdf5_totals);
  OK(haptic_recorder_close(csv, &csv_totals, &err));
  OK(haptic_recorder_close(hdf5, &hdf5_totals, &err));
  CHECK(csv_totals.samples_received == after.accepted - before.accepted);
  CHECK(csv_totals.samples_written == csv_totals.samples_received && csv_totals.dropped == 0u);
  CHECK(csv_totals.write_errors == 0u && csv_totals.first_error[0] == '\0');
  CHECK(csv_totals.events_written >= 1u);  /* watch_started at least */
  CHECK(hdf5_totals.samples_written == csv_totals.samples_received && hdf5_totals.dropped == 0u);
  CHECK(seen.count > 0 && seen.count <= csv_totals.samples_received);
  CHECK(write_seen(&seen, seen_path) == 0);
  OK(haptic_client_close(client, &err));
  pthread_mutex_destroy(&seen.lock);
  if (failures > 0) fprintf(stderr, "last error: %d %s\n", err.code, err.message);
  return failures;
}
