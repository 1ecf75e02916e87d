// A reused lockstep server reproduces a run (issue 11 item 5): Reset puts the simulated device,
// its operator, the ticks and the scene back as the server started, so the same calls give the
// same samples bit for bit; it refuses, changing nothing, in real time or while another session
// holds items.

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <future>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "haptic/client.hpp"
#include "integration/sdk_harness.hpp"
#include "integration/server_process.hpp"

namespace haptic::test {
namespace {

using std::chrono::milliseconds;
using std::chrono::seconds;

// The server's own scene: a spring field the tool always feels, so that its re-creation counts.
constexpr const char* kInitialScene = R"("initial_scene": {"fields": [
    {"spring_to_point": {"anchor": {"x": 0.005, "z": 0.02}, "stiffness": 5}}]})";

/// What one run leaves: every stepped sample, the items' ids, energies and pushed masses.
struct ScriptedRun {
  std::vector<State> states;
  std::vector<std::uint64_t> ids;
  std::vector<ItemEnergy> energy;
  std::vector<ObjectState> masses;
  std::vector<ObjectHandle> objects;  // kept, so the items stay for the next checks
  std::vector<FieldHandle> fields;
};

/// One scripted run: a wall, a pushable sphere and a spring; the hand drives the tool down
/// through them; the wall is stiffened halfway.
ScriptedRun drive(Client& client) {
  ScriptedRun run;
  run.objects.push_back(client.add_wall({.normal = {0, 0, 1}, .impedance = {1200.0, 2.0}}));
  run.objects.push_back(client.add_sphere({.center = {0.0, 0.004, 0.035},
                                           .radius = 0.01,
                                           .impedance = {800.0, 1.0},
                                           .dynamics = {.mass = 0.5, .damping = 1.0}}));
  run.fields.push_back(client.add_spring_field({.anchor = {0.01, 0, 0.03}, .stiffness = 30.0, .damping = 0.2}));
  client.set_operator(OperatorInput::follow_line({0, 0.002, 0.05}, {0, 0, -0.008}, 0.25,
                                                 OperatorInput::Grip::kTight));
  for (int i = 0; i < 40; ++i) {
    if (i == 20) run.objects[0].update(WallSpec{.normal = {0, 0, 1}, .impedance = {1500.0, 2.0}});
    run.states.push_back(step_and_get(client, 10));
  }
  for (const ObjectHandle& handle : run.objects) run.ids.push_back(handle.id());
  for (const FieldHandle& handle : run.fields) run.ids.push_back(handle.id());
  run.energy = client.scene_energy();
  run.masses = client.object_states();
  return run;
}

void expect_same(const Vec3& a, const Vec3& b, const char* what, std::uint64_t tick) {
  // Bit for bit: the same operations in the same order.
  EXPECT_TRUE(a.x == b.x && a.y == b.y && a.z == b.z)
      << what << " at tick " << tick << ": (" << a.x << ", " << a.y << ", " << a.z << ") vs (" << b.x
      << ", " << b.y << ", " << b.z << ")";
}

TEST(LockstepReset, TheSameCallsAfterAResetGiveTheSameRunBitForBit) {
  ServerProcess server(lockstep_config(kInitialScene));
  Client client(config_for(server, "scripted"));
  // A second session that only watches: it holds no items, so it does not stand in the way.
  std::vector<Event> events;
  std::mutex events_mutex;
  Client observer(config_for(server, "observer"));
  observer.on_event([&](const Event& event) {
    std::lock_guard lock(events_mutex);
    events.push_back(event);
  });

  ScriptedRun first = drive(client);
  ASSERT_EQ(first.states.back().tick, 400u);
  double largest = 0.0;
  for (const State& state : first.states) largest = std::max(largest, std::abs(state.force.z));
  EXPECT_GT(largest, 1.0) << "the run never pressed into anything";

  client.reset();
  EXPECT_EQ(client.stats().objects, 0u);
  EXPECT_EQ(client.stats().fields, 1u);  // the server's own spring, made again
  EXPECT_THROW(first.objects[0].update(WallSpec{.normal = {0, 0, 1}}), NotFoundError);  // stale
  State observed;
  ASSERT_TRUE(observer.wait_for_tick(observer.step(1), observed, seconds(5)));
  EXPECT_EQ(observed.tick, 1u);  // the stream carries on, from tick 1
  client.reset();                 // and back again, so the second run starts where the first did
  // The observer's stream (datagrams, not Step replies: sequence > 0) goes on from tick 1 too.
  State streamed;
  const auto give_up = std::chrono::steady_clock::now() + seconds(5);
  do {
    (void)client.step(1);
  } while (!(observer.poll_state(streamed, milliseconds(20)) && streamed.sequence > 0 && streamed.tick <= 40) &&
           std::chrono::steady_clock::now() < give_up);
  EXPECT_GT(streamed.sequence, 0u);
  EXPECT_LE(streamed.tick, 40u) << "the observer's stream still shows the old run";
  client.reset();                 // the run starts from tick 1 again

  const ScriptedRun second = drive(client);
  ASSERT_EQ(second.states.size(), first.states.size());
  for (std::size_t i = 0; i < first.states.size(); ++i) {
    const State& a = first.states[i];
    const State& b = second.states[i];
    ASSERT_EQ(a.tick, b.tick);
    EXPECT_EQ(a.server_time, b.server_time);
    expect_same(a.position, b.position, "position", a.tick);
    expect_same(a.velocity, b.velocity, "velocity", a.tick);
    expect_same(a.force, b.force, "force", a.tick);
    expect_same(a.proxy, b.proxy, "proxy", a.tick);
    EXPECT_EQ(a.contact_count, b.contact_count);
    EXPECT_EQ(a.flags, b.flags) << "flags at tick " << a.tick;
  }
  EXPECT_EQ(second.ids, first.ids);  // ids count from the same place
  ASSERT_EQ(second.energy.size(), first.energy.size());
  for (std::size_t i = 0; i < first.energy.size(); ++i) {
    EXPECT_EQ(second.energy[i].id, first.energy[i].id);
    // Equal but for the last bits: an updated item's old version's meter is added to the new
    // one's when housekeeping drops it, at a tick wall-clock time chooses, so the sum's order
    // (and rounding) can differ. Every force and position above is bit for bit.
    EXPECT_NEAR(second.energy[i].given_to_device, first.energy[i].given_to_device,
                1e-12 * std::abs(first.energy[i].given_to_device));
    EXPECT_NEAR(second.energy[i].absorbed_from_device, first.energy[i].absorbed_from_device,
                1e-12 * std::abs(first.energy[i].absorbed_from_device));
  }
  ASSERT_EQ(second.masses.size(), 1u);
  expect_same(second.masses[0].position, first.masses[0].position, "pushed sphere", 400);
  std::lock_guard lock(events_mutex);
  EXPECT_EQ(std::count_if(events.begin(), events.end(),
                          [](const Event& e) { return e.kind == Event::Kind::kReset; }),
            3);
}

// A client that steps from inside its own on_state callback while another of its threads resets
// the server: each reset restarts the client's tick stream, and the callback's steps learn of
// the new run too. Neither waits for the other's thread (the stream's restart takes the receive
// lock, which the callback never holds), so twenty resets finish while the callback keeps going.
TEST(LockstepReset, ACallbackThatStepsAndResetsOnAnotherThreadNeverWaitForEachOther) {
  ServerProcess server(lockstep_config(kInitialScene));
  Client client(config_for(server, "stepper"));
  std::atomic<int> callback_steps{0};
  std::atomic<bool> stepping{true};
  client.on_state([&](const State&) {
    if (!stepping.load()) return;
    try {
      (void)client.step(1);
      ++callback_steps;
    } catch (const Error&) {
      // a step refused while the reset holds the server: the next State tries again
    }
  });
  (void)client.step(1);  // the first State starts the callback's stepping
  auto resets = std::async(std::launch::async, [&] {
    for (int i = 0; i < 20; ++i) {
      client.reset();
      (void)client.step(1);  // a State after each reset, so the callback runs again
    }
  });
  if (resets.wait_for(seconds(30)) != std::future_status::ready) {
    ADD_FAILURE() << "the resets and the callback's steps wait on each other";
    std::_Exit(1);  // a deadlocked client cannot be destroyed
  }
  resets.get();
  // The callback's chain of steps goes on after the resets (each of its steps brings the State
  // that calls it again); on a loaded machine every one of its steps may have met a reset, and
  // the States of the last reset's step may still be on their way: look for its steps a while.
  const auto deadline = std::chrono::steady_clock::now() + seconds(10);
  while (callback_steps.load() == 0 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(milliseconds(1));
  }
  stepping = false;
  client.on_state({});
  EXPECT_GT(callback_steps.load(), 0);
  State state;
  EXPECT_TRUE(client.wait_for_tick(client.step(1), state, seconds(5)));  // still streaming
}

TEST(LockstepReset, IsRefusedChangingNothingWhileAnotherSessionHoldsItems) {
  ServerProcess server(lockstep_config());
  Client client(config_for(server, "resetter"));
  Client other(config_for(server, "other"));
  ObjectHandle mine = client.add_wall({.normal = {0, 0, 1}, .impedance = {500.0, 1.0}});
  ObjectHandle theirs = other.add_wall({.point = {0, 0, -0.05}, .normal = {0, 0, 1}, .impedance = {500.0, 1.0}});
  const std::uint64_t before = client.step(30);
  try {
    client.reset();
    ADD_FAILURE() << "reset went ahead under another session's items";
  } catch (const FailedPreconditionError& error) {
    // The session id as every other message writes it: 16 hex digits.
    char id[17];
    std::snprintf(id, sizeof id, "%016llx", static_cast<unsigned long long>(other.session_id()));
    EXPECT_EQ(std::string(error.what()).rfind("Reset: session " + std::string(id) +
                                                  " holds 1 objects and fields",
                                              0),
              0u)
        << error.what();
  }
  EXPECT_EQ(client.step(1), before + 1);  // the ticks went on
  EXPECT_EQ(client.stats().objects, 2u);
  EXPECT_NO_THROW(mine.update(WallSpec{.normal = {0, 0, 1}, .impedance = {600.0, 1.0}}));
  theirs.remove();
  EXPECT_NO_THROW(client.reset());  // a removed item is gone at once: nothing stands in the way
  EXPECT_EQ(client.step(1), 1u);
}

TEST(LockstepReset, IsRefusedInRealTime) {
  ServerProcess server(R"({"time_mode": "REAL_TIME", "udp_address": "127.0.0.1", "status_period_s": 0,
      "real_time": {"use_fifo": false}})");
  Client client(config_for(server, "realtime"));
  try {
    client.reset();
    ADD_FAILURE() << "a real-time server was reset";
  } catch (const FailedPreconditionError& error) {
    EXPECT_EQ(std::string(error.what()), "Reset: only a LOCKSTEP server can be reset; this one runs in real time");
  }
}

}  // namespace
}  // namespace haptic::test
