#pragma once
// The federation's thread between the loop and DDS (docs/federation.md). Every period it
//   - takes the other sites' tools from its transport into each port's mailbox of remote tools
//     (a slot per remote tool, kept while it stays), with the energy each one's coupling sent us;
//   - reads each device port's newest sample from its SampleRing and, when the port has ticked
//     since, publishes it through the transport with what this port's couplings sent (the
//     ledger), and as ROS 2 topics (ros2_topics) where configured;
//   - takes the other sites' copies of the shared masses into the loop's mailbox, and publishes
//     this site's copies when the loop has moved them;
//   - with ros2.wrench_topic, takes each port's ROS 2 wrench (a robot's) into its mailbox, refusing
//     one in another frame or with a NaN or infinity (counted, and logged once per port and reason);
//   - logs each other site's arrival, its going quiet (nothing from it for silence_s) and its
//     return, one line each, rate-limited per site (LogLimiter);
//   - treats every other site as possibly wrong or hostile: a sample whose site is not the one its
//     writer speaks for (the writer's partition, which DDS Security binds to the writer's
//     identity), or with a NaN or an infinity, is refused, counted and logged; the energy another
//     site says it sent is credited per coupling only up to the CreditCap, and a site whose books
//     do not add up (CreditAccount) is cut off: nothing more is taken from it while this relay
//     runs, and that is logged.
// The loop never waits on it, and a sample nobody asked for is never converted.

#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "federation/credit_account.hpp"
#include "federation/dds_participant.hpp"
#include "federation/log_limiter.hpp"
#include "federation/mass_topic.hpp"
#include "federation/options.hpp"
#include "federation/ros2_topics.hpp"
#include "federation/tool_topic.hpp"
#include "federation/transport.hpp"
#include "runtime/latest_value.hpp"
#include "runtime/remote_tools.hpp"
#include "runtime/robot_wrench.hpp"
#include "runtime/sample_ring.hpp"
#include "runtime/shared_masses.hpp"

namespace haptic::federation {

/// One port's ring, the buttons its device reports, and (with the tool topic) its mailbox of
/// remote tools and the ledger of its couplings. Not owned.
struct RelayPort {
  const runtime::SampleRing* samples = nullptr;
  std::uint32_t buttons = 0;
  runtime::LatestValue<runtime::RemoteToolSet>* remote = nullptr;
  const runtime::CouplingLedger* ledger = nullptr;
  /// With ros2.wrench_topic: the mailbox of the ROS 2 node's wrench for this port's tool.
  runtime::LatestValue<runtime::RobotWrench>* robot = nullptr;
};

/// The masses shared across sites (runtime/shared_masses): the loop's table of this site's copies
/// (read and published) and its mailbox of the other sites' copies (written). Not owned; both
/// null: no mass topic.
struct RelayMasses {
  const runtime::LatestValue<runtime::LocalMassTable>* local = nullptr;
  runtime::LatestValue<runtime::RemoteMassTable>* remote = nullptr;
};

class SampleRelay {
 public:
  /// Joins the domain and makes the writers (off the loop): a DdsTransport on the site's
  /// participant, and the ROS 2 topics where configured. Throws std::runtime_error naming what
  /// was refused, except the mass topic's writer (masses_refused()).
  SampleRelay(const RelayOptions& options, const std::vector<RelayPort>& ports, RelayMasses masses = {});
  /// Over `transport` (not owned), without a participant or ROS 2 topics (options.domain and
  /// options.ros2 are not used): lockstep tests step it with their own clock.
  SampleRelay(const RelayOptions& options, Transport& transport, const std::vector<RelayPort>& ports,
              RelayMasses masses = {});
  ~SampleRelay();
  SampleRelay(const SampleRelay&) = delete;
  SampleRelay& operator=(const SampleRelay&) = delete;

  /// The thread: step(steady_clock::now()) once a period.
  void start();
  void stop();
  /// One period at time `now` (remote tools and copies silent since before now − silence_s are
  /// dropped): receive, publish, the masses, the ROS 2 wrenches. While start() has no thread
  /// running (lockstep tests).
  void step(std::chrono::steady_clock::time_point now);
  /// Why this site's mass copies are not published ("" when they are): an observer's
  /// permissions refuse the mass topic's writer.
  const std::string& masses_refused() const { return masses_refused_; }
  /// Why this site's tools are not published on the tool topic ("" when they are): an observer's
  /// permissions refuse that writer too (the ROS 2 topics still carry them).
  const std::string& tools_refused() const { return tools_refused_; }
  /// The site's participant in the domain (the shared scene's replicator joins through it); only
  /// from the first constructor.
  const Participant& participant() const { return *participant_; }
  /// Samples published so far (all ports), and publications DDS refused.
  std::uint64_t published() const { return published_.load(std::memory_order_relaxed); }
  std::uint64_t failed() const { return failed_.load(std::memory_order_relaxed); }
  /// ROS 2 wrenches taken into the mailboxes so far (all ports), and those refused (another
  /// frame_id, a NaN or an infinity).
  std::uint64_t wrenches_accepted() const { return wrenches_accepted_.load(std::memory_order_relaxed); }
  std::uint64_t wrenches_refused() const { return wrenches_refused_.load(std::memory_order_relaxed); }
  /// Other sites' tool and mass samples refused so far: naming a site their writer does not speak
  /// for, holding a NaN or an infinity, or from a site cut off.
  std::uint64_t samples_refused() const { return samples_refused_.load(std::memory_order_relaxed); }
  /// Energy other sites claimed to have sent and were not credited (over the cap), cumulative. J.
  double energy_refused() const { return energy_refused_.load(std::memory_order_relaxed); }
  /// Sites cut off so far (their books did not add up).
  std::uint64_t sites_cut_off() const { return sites_cut_off_.load(std::memory_order_relaxed); }

 private:
  void run();
  void receive(std::chrono::steady_clock::time_point now);
  void publish();
  void receive_masses(std::chrono::steady_clock::time_point now);
  void publish_masses();
  void receive_wrenches();
  /// A sample from `site` arrived at `now`.
  void heard(const std::string& site, std::chrono::steady_clock::time_point now);
  /// Sites quiet since before now − silence_s are gone; what changed is logged.
  void watch_sites(std::chrono::steady_clock::time_point now);
  /// Whether a sample naming `site`, from a writer speaking for `writer_site` (unset: the
  /// transport cannot say), with finite values or not, is taken; what is not is counted and logged.
  bool admit(const std::string& site, const std::optional<std::string>& writer_site, bool finite, const char* what,
             std::chrono::steady_clock::time_point now);
  /// Whether the site of this key is cut off.
  bool cut_off_key(engine::SiteKey site) const;
  /// Which coupling a claim is for, named only in a cut-off's log line: a remote tool's port and
  /// this site's, or (remote_port < 0) a copy of a shared mass.
  struct CouplingName {
    long remote_port = -1;
    long local_port = -1;
  };
  /// Credits a claimed total on `account`; a claim that shows the site's books do not add up cuts
  /// the site off (logged) and returns false.
  bool credit(CreditAccount& account, double claimed, const std::string& site, CouplingName name,
              std::chrono::steady_clock::time_point now);

  /// Which remote tool each mailbox slot of a port holds.
  struct Slot {
    std::string site;
    std::uint32_t port = 0;
    bool used = false;
    std::chrono::steady_clock::time_point heard;  // its newest sample's arrival
    CreditAccount credit;                         // what its coupling with this port claims it sent
  };

  RelayOptions options_;
  std::vector<RelayPort> ports_;
  std::unique_ptr<Participant> participant_;    // from the first constructor
  std::unique_ptr<DdsTransport> dds_;            // over participant_
  Transport* transport_ = nullptr;               // dds_, or the caller's
  std::vector<std::unique_ptr<Ros2ToolPublisher>> ros2_;  // per port, when configured
  /// Per port, with ros2.wrench_topic and a mailbox (else null); whether each port has logged a
  /// refusal for its frame, and for a NaN.
  std::vector<std::unique_ptr<Ros2WrenchSubscriber>> wrenches_in_;
  std::vector<std::array<bool, 2>> wrench_logged_;
  std::vector<std::array<Slot, runtime::kMaxRemoteTools>> slots_;  // per port
  std::vector<ToolState> received_;                                 // scratch
  std::vector<std::uint64_t> last_tick_;                  // per port: the newest tick published
  RelayMasses masses_;
  bool masses_on_ = false;                                 // both mailboxes given
  std::string masses_refused_;
  std::string tools_refused_;
  std::vector<MassState> received_masses_;                 // scratch
  /// When each copy in the mailbox of remote masses was last heard ([mass][copy]).
  std::array<std::array<std::chrono::steady_clock::time_point, engine::kMaxRemoteCopies>, runtime::kMaxSharedMasses>
      mass_heard_{};
  /// What each copy's coupling with this site's copy claims it sent ([mass][copy]).
  std::array<std::array<CreditAccount, engine::kMaxRemoteCopies>, runtime::kMaxSharedMasses> mass_credit_{};
  std::uint64_t last_mass_tick_ = 0;
  std::uint64_t periods_ = 0;                             // run()'s periods so far
  /// Each other site ever heard: when last, and whether it is heard now.
  struct Peer {
    std::chrono::steady_clock::time_point heard;
    bool present = false;
  };
  std::map<std::string, Peer> peers_;
  std::set<std::string> cut_off_;                          // sites whose books did not add up
  LogLimiter peer_log_;
  std::vector<std::string> log_lines_;                     // scratch
  std::thread thread_;
  std::atomic<bool> stopping_{false};
  std::atomic<std::uint64_t> published_{0};
  std::atomic<std::uint64_t> failed_{0};
  std::atomic<std::uint64_t> wrenches_accepted_{0};
  std::atomic<std::uint64_t> wrenches_refused_{0};
  std::atomic<std::uint64_t> samples_refused_{0};
  std::atomic<double> energy_refused_{0.0};
  std::atomic<std::uint64_t> sites_cut_off_{0};
};

}  // namespace haptic::federation
