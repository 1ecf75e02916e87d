// One-way latency of the federation's tool topic (server/federation/tool_topic.hpp) between sites
// in network namespaces, against a bare UDP floor measured in the same run (docs/federation.md).
// federation_latency_netns.sh makes the namespaces and runs the roles below. A benchmark: it
// prints figures and the targets beside them, and asserts nothing about time.
//
// Every site publishes one tool at 1 kHz and receives every other site's: over the tool topic
// (Cyclone DDS, unicast discovery between the namespaces' addresses) or over plain UDP sockets,
// one datagram to each peer carrying the same fields in the same encoding (the sample's CDR, so
// the same size). The send time goes in the sample (ToolState::time_ns, CLOCK_MONOTONIC, which the
// namespaces share); the receiving side stamps each sample once it is in hand: UDP's receiving
// thread after recv, DDS's listener after take on Cyclone's receive thread (one thread woken per
// datagram either way). A 1 kHz loop reads the newest sample per remote site as the receiving
// side leaves it (the relay's mailboxes, sample_relay.hpp) and records how far the oldest in hand
// is behind the newest sent time received so far ("staleness").
//
// Roles:
//   clock    prints CLOCK_MONOTONIC in ns (the script's common start time)
//   site     --transport udp|dds|dds-waitset --index I --addresses A0,A1,... --start-ns T
//            --seconds S --round R --out FILE: one site, measured from T for S seconds; its
//            records to FILE. dds takes in a listener, dds-waitset in a thread a waitset wakes.
//   summary  DIR: one line for one configuration (the sites' files in DIR)
//   report   DIR...: the table, each configuration's DDS/UDP ratios and the targets

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cerrno>
#include <charconv>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <dds/dds.h>

#include "federation/dds_participant.hpp"
#include "federation/tool_topic.hpp"

namespace {

using haptic::federation::ToolState;

constexpr std::int64_t kPeriodNs = 1'000'000;           // every site's publishing rate: 1 kHz
constexpr std::int64_t kDrainNs = 300'000'000;          // the receiver's wait after the window
constexpr std::int64_t kReceiveWaitNs = 20'000'000;    // the receiver's longest wait, to see the end
constexpr std::int64_t kStaleLimitNs = 2'000'000;       // the target: none older than this
constexpr std::uint16_t kUdpPort = 7390;                // below DDSI's 7400 ... of domain 0
constexpr std::uint32_t kDomain = 0;                    // each namespace is a network of its own
constexpr double kTargetP50Ratio = 2.0;
constexpr double kTargetP99Ratio = 3.0;

[[noreturn]] void fail(const std::string& message) {
  std::fprintf(stderr, "federation_latency_bench: %s\n", message.c_str());
  std::exit(2);
}

std::int64_t now_ns() {
  timespec t{};
  clock_gettime(CLOCK_MONOTONIC, &t);
  return static_cast<std::int64_t>(t.tv_sec) * 1'000'000'000 + t.tv_nsec;
}

/// CPU time of the whole process (every thread, Cyclone's too). Unit: ns.
std::int64_t process_cpu_ns() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<std::int64_t>(t.tv_sec) * 1'000'000'000 + t.tv_nsec;
}

void sleep_until_ns(std::int64_t t_ns) {
  const timespec t{static_cast<time_t>(t_ns / 1'000'000'000), static_cast<long>(t_ns % 1'000'000'000)};
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &t, nullptr) == EINTR) {
  }
}

std::string site_name(int index) { return "site-" + std::to_string(index); }

/// The index in "site-<i>", or -1.
int site_index(const std::string& name) {
  if (name.rfind("site-", 0) != 0) return -1;
  int index = -1;
  const char* begin = name.data() + 5;
  const auto [end, error] = std::from_chars(begin, name.data() + name.size(), index);
  return error == std::errc() && end == name.data() + name.size() ? index : -1;
}

/// A site's tool as a loop would publish it, with one coupling per other site (a tool touching all
/// the others: the largest sample the federation sends, kMaxCouplings at most).
ToolState tool_of(int index, int sites) {
  ToolState tool;
  tool.site = site_name(index);
  tool.port = 0;
  tool.p_WT = {0.01 * index, -0.02, 0.03};
  tool.v_WT = {0.1, 0.0, -0.1};
  tool.F_T_W = {0.0, 0.0, 1.5};
  tool.R_WT = {0.0, 0.0, 0.0, 1.0};
  for (int other = 0; other < sites && tool.energy.size() < haptic::federation::kMaxCouplings; ++other) {
    if (other != index) tool.energy.push_back({site_name(other), 0, 1e-3 * other});
  }
  return tool;
}

// --- The UDP floor's encoding: the IDL's fields as XCDR1 little endian (4-byte encapsulation
// header, natural alignment from after it, bounded strings as length + characters + NUL), the
// serialized payload DDS carries for the same sample.

class CdrWriter {
 public:
  CdrWriter(std::uint8_t* buffer, std::size_t capacity) : buffer_(buffer), capacity_(capacity) {
    put_bytes("\x00\x01\x00\x00", 4);  // CDR_LE
  }
  void u32(std::uint32_t v) { put_aligned(v); }
  void u64(std::uint64_t v) { put_aligned(v); }
  void f64(double v) { put_aligned(std::bit_cast<std::uint64_t>(v)); }
  void text(const std::string& s) {
    u32(static_cast<std::uint32_t>(s.size() + 1));
    put_bytes(s.data(), s.size());
    put_bytes("", 1);
  }
  std::size_t size() const { return overflow_ ? 0 : pos_; }

 private:
  template <class T>
  void put_aligned(T v) {
    while ((pos_ - 4) % sizeof(T) != 0) put_bytes("", 1);
    std::uint8_t bytes[sizeof(T)];
    for (std::size_t i = 0; i < sizeof(T); ++i) bytes[i] = static_cast<std::uint8_t>(v >> (8 * i));
    put_bytes(bytes, sizeof(T));
  }
  void put_bytes(const void* data, std::size_t n) {
    if (pos_ + n > capacity_) {
      overflow_ = true;
      return;
    }
    std::memcpy(buffer_ + pos_, data, n);
    pos_ += n;
  }
  std::uint8_t* buffer_;
  std::size_t capacity_;
  std::size_t pos_ = 0;
  bool overflow_ = false;
};

class CdrReader {
 public:
  CdrReader(const std::uint8_t* data, std::size_t size) : data_(data), size_(size), pos_(4), ok_(size >= 4) {}
  std::uint32_t u32() { return get_aligned<std::uint32_t>(); }
  std::uint64_t u64() { return get_aligned<std::uint64_t>(); }
  double f64() { return std::bit_cast<double>(u64()); }
  std::string text(std::size_t bound) {
    const std::uint32_t n = u32();
    if (!ok_ || n == 0 || n > bound + 1 || pos_ + n > size_) {
      ok_ = false;
      return {};
    }
    std::string s(reinterpret_cast<const char*>(data_ + pos_), n - 1);
    pos_ += n;
    return s;
  }
  bool ok() const { return ok_; }

 private:
  template <class T>
  T get_aligned() {
    while ((pos_ - 4) % sizeof(T) != 0) ++pos_;
    if (!ok_ || pos_ + sizeof(T) > size_) {
      ok_ = false;
      return 0;
    }
    T v = 0;
    for (std::size_t i = 0; i < sizeof(T); ++i) v |= static_cast<T>(data_[pos_ + i]) << (8 * i);
    pos_ += sizeof(T);
    return v;
  }
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_;
  bool ok_;
};

std::size_t encode(const ToolState& tool, std::uint8_t* buffer, std::size_t capacity) {
  CdrWriter w(buffer, capacity);
  w.text(tool.site);
  w.u32(tool.port);
  w.u64(tool.tick);
  w.u64(static_cast<std::uint64_t>(tool.time_ns));
  for (const auto* v : {&tool.p_WT, &tool.v_WT, &tool.F_T_W}) {
    w.f64(v->x);
    w.f64(v->y);
    w.f64(v->z);
  }
  w.f64(tool.R_WT.w);
  w.f64(tool.R_WT.x);
  w.f64(tool.R_WT.y);
  w.f64(tool.R_WT.z);
  w.u32(tool.buttons);
  w.u32(static_cast<std::uint32_t>(tool.energy.size()));
  for (const auto& e : tool.energy) {
    w.text(e.site);
    w.u32(e.port);
    w.f64(e.sent);
  }
  return w.size();
}

bool decode(const std::uint8_t* data, std::size_t size, ToolState& tool) {
  CdrReader r(data, size);
  tool.site = r.text(64);
  tool.port = r.u32();
  tool.tick = r.u64();
  tool.time_ns = static_cast<std::int64_t>(r.u64());
  for (auto* v : {&tool.p_WT, &tool.v_WT, &tool.F_T_W}) {
    v->x = r.f64();
    v->y = r.f64();
    v->z = r.f64();
  }
  tool.R_WT.w = r.f64();
  tool.R_WT.x = r.f64();
  tool.R_WT.y = r.f64();
  tool.R_WT.z = r.f64();
  tool.buttons = r.u32();
  const std::uint32_t couplings = r.u32();
  if (!r.ok() || couplings > haptic::federation::kMaxCouplings) return false;
  tool.energy.clear();
  for (std::uint32_t i = 0; i < couplings; ++i) {
    haptic::federation::CouplingEnergy e;
    e.site = r.text(64);
    e.port = r.u32();
    e.sent = r.f64();
    tool.energy.push_back(std::move(e));
  }
  return r.ok();
}

// --- What a site's receiving side records: each sample's one-way latency when sent in the window,
// and the newest sent time per site for the loop. One deliverer at a time (the receiving thread,
// or Cyclone's receive thread through a listener).

class Received {
 public:
  Received(int sites, int own, std::int64_t start_ns, std::int64_t end_ns, std::size_t capacity)
      : sites_(sites), own_(own), start_ns_(start_ns), end_ns_(end_ns),
        newest_(new std::atomic<std::int64_t>[static_cast<std::size_t>(sites)]),
        received_(static_cast<std::size_t>(sites), 0) {
    for (int s = 0; s < sites; ++s) newest_[static_cast<std::size_t>(s)].store(0);
    latency_ns_.reserve(capacity);
  }

  /// Samples in hand at `arrival_ns`.
  void deliver(const std::vector<ToolState>& batch, std::int64_t arrival_ns) {
    const std::lock_guard<std::mutex> lock(mutex_);
    for (const ToolState& tool : batch) {
      const int from = site_index(tool.site);
      if (from < 0 || from >= sites_ || from == own_) {
        ++foreign_;
        continue;
      }
      auto& slot = newest_[static_cast<std::size_t>(from)];
      if (tool.time_ns > slot.load(std::memory_order_relaxed)) slot.store(tool.time_ns, std::memory_order_release);
      if (tool.time_ns >= start_ns_ && tool.time_ns < end_ns_) {
        latency_ns_.push_back(arrival_ns - tool.time_ns);
        ++received_[static_cast<std::size_t>(from)];
      }
    }
  }

  /// The newest sent time heard from `site` (0: none yet); the loop's read.
  std::int64_t newest(int site) const { return newest_[static_cast<std::size_t>(site)].load(std::memory_order_acquire); }

  // After the receiving side has stopped.
  const std::vector<std::int64_t>& latency_ns() const { return latency_ns_; }
  std::uint64_t received(int site) const { return received_[static_cast<std::size_t>(site)]; }
  std::uint64_t foreign() const { return foreign_; }

 private:
  int sites_, own_;
  std::int64_t start_ns_, end_ns_;
  std::mutex mutex_;
  std::unique_ptr<std::atomic<std::int64_t>[]> newest_;
  std::vector<std::int64_t> latency_ns_;
  std::vector<std::uint64_t> received_;
  std::uint64_t foreign_ = 0;
};

// --- The transports, as the site's threads use them.

class Transport {
 public:
  virtual ~Transport() = default;
  /// Sends one sample to every other site.
  virtual bool send(const ToolState& tool) = 0;
  /// The receiving thread's step: waits up to kReceiveWaitNs for samples from the other sites and
  /// delivers them.
  virtual void receive(Received& into) = 0;
  /// "readers/writers matched" (DDS discovery), or "".
  virtual std::string matched() const { return {}; }
};

class UdpTransport final : public Transport {
 public:
  UdpTransport(const std::vector<std::string>& addresses, int index) {
    socket_ = ::socket(AF_INET, SOCK_DGRAM, 0);
    if (socket_ < 0) fail(std::string("socket: ") + std::strerror(errno));
    for (std::size_t i = 0; i < addresses.size(); ++i) {
      sockaddr_in a{};
      a.sin_family = AF_INET;
      a.sin_port = htons(kUdpPort);
      if (inet_pton(AF_INET, addresses[i].c_str(), &a.sin_addr) != 1) fail("not an IPv4 address: " + addresses[i]);
      if (static_cast<int>(i) == index) {
        if (bind(socket_, reinterpret_cast<const sockaddr*>(&a), sizeof a) != 0) {
          fail("bind " + addresses[i] + ": " + std::strerror(errno));
        }
      } else {
        peers_.push_back(a);
      }
    }
    const timeval wait{0, static_cast<suseconds_t>(kReceiveWaitNs / 1000)};
    setsockopt(socket_, SOL_SOCKET, SO_RCVTIMEO, &wait, sizeof wait);
  }
  ~UdpTransport() override { ::close(socket_); }

  bool send(const ToolState& tool) override {
    const std::size_t n = encode(tool, send_buffer_, sizeof send_buffer_);
    if (n == 0) return false;
    bool ok = true;
    for (const sockaddr_in& peer : peers_) {
      ok = sendto(socket_, send_buffer_, n, 0, reinterpret_cast<const sockaddr*>(&peer), sizeof peer) ==
               static_cast<ssize_t>(n) &&
           ok;
    }
    return ok;
  }

  void receive(Received& into) override {
    batch_.clear();
    int flags = 0;
    for (;;) {
      const ssize_t n = recv(socket_, receive_buffer_, sizeof receive_buffer_, flags);
      if (n <= 0) break;
      ToolState tool;
      if (decode(receive_buffer_, static_cast<std::size_t>(n), tool)) batch_.push_back(std::move(tool));
      flags = MSG_DONTWAIT;  // then whatever else has arrived, without waiting
    }
    if (!batch_.empty()) into.deliver(batch_, now_ns());
  }

 private:
  int socket_ = -1;
  std::vector<sockaddr_in> peers_;
  std::uint8_t send_buffer_[2048];
  std::uint8_t receive_buffer_[2048];
  std::vector<ToolState> batch_;
};

/// The tool topic's reader that ToolSubscriber made under `participant` (participant → its
/// implicit subscriber → the reader): ToolSubscriber keeps it to itself, and the bench is woken by
/// it rather than poll.
dds_entity_t find_reader(dds_entity_t participant) {
  dds_entity_t children[16];
  const dds_return_t n = dds_get_children(participant, children, 16);
  for (dds_return_t i = 0; i < std::min<dds_return_t>(n, 16); ++i) {
    dds_entity_t grandchildren[16];
    const dds_return_t m = dds_get_children(children[i], grandchildren, 16);
    for (dds_return_t k = 0; k < std::min<dds_return_t>(m, 16); ++k) {
      if (dds_get_subscriber(grandchildren[k]) <= 0) continue;  // only a reader has one
      char topic[64] = {};
      if (dds_get_name(dds_get_topic(grandchildren[k]), topic, sizeof topic) >= 0 &&
          std::strcmp(topic, haptic::federation::kToolTopic) == 0) {
        return grandchildren[k];
      }
    }
  }
  return 0;
}

/// How a DDS site takes what arrived: in a listener, on Cyclone's receive thread (as UDP's
/// receiving thread is the one the kernel wakes), or in a thread of its own woken by a waitset
/// (one more thread switch per batch).
enum class DdsReceive { kListener, kWaitset };

class DdsTransport final : public Transport {
 public:
  DdsTransport(const std::vector<std::string>& addresses, int index, DdsReceive mode, Received& into)
      : participant_(options(addresses, index)), publisher_(participant_, site_name(index)), subscriber_(participant_),
        mode_(mode), into_(into) {
    reader_ = find_reader(participant_.handle());
    if (reader_ <= 0) fail("the tool topic's reader was not found under the participant");
    if (mode == DdsReceive::kListener) {
      dds_listener_t* listener = dds_create_listener(this);
      dds_lset_data_available(listener, &DdsTransport::on_data_available);
      const dds_return_t set = dds_set_listener(reader_, listener);
      dds_delete_listener(listener);
      if (set != DDS_RETCODE_OK) fail("cannot listen on the tool topic's reader: " + haptic::federation::dds_error(set));
    } else {
      waitset_ = dds_create_waitset(participant_.handle());
      const dds_entity_t condition = dds_create_readcondition(reader_, DDS_ANY_STATE);
      if (waitset_ < 0 || condition < 0 || dds_waitset_attach(waitset_, condition, 0) != DDS_RETCODE_OK) {
        fail("cannot wait on the tool topic's reader");
      }
    }
  }
  ~DdsTransport() override {
    if (mode_ == DdsReceive::kListener) dds_set_listener(reader_, nullptr);
  }

  bool send(const ToolState& tool) override { return publisher_.publish(tool); }

  void receive(Received& into) override {
    if (mode_ == DdsReceive::kListener) {
      sleep_until_ns(now_ns() + kReceiveWaitNs);  // the listener delivers
      return;
    }
    if (dds_waitset_wait(waitset_, nullptr, 0, kReceiveWaitNs) <= 0) return;
    take_into(into);
  }

  std::string matched() const override {
    return std::to_string(publisher_.matched_readers()) + " " + std::to_string(subscriber_.matched_writers());
  }

 private:
  static haptic::federation::DomainOptions options(const std::vector<std::string>& addresses, int index) {
    haptic::federation::DomainOptions o;
    o.domain_id = kDomain;
    o.interface = addresses[static_cast<std::size_t>(index)];
    for (std::size_t i = 0; i < addresses.size(); ++i) {
      if (static_cast<int>(i) != index) o.peers.push_back(addresses[i]);
    }
    return o;
  }

  static void on_data_available(dds_entity_t, void* self) {
    auto* transport = static_cast<DdsTransport*>(self);
    transport->take_into(transport->into_);
  }

  void take_into(Received& into) {
    batch_.clear();
    if (subscriber_.take(batch_) > 0) into.deliver(batch_, now_ns());
  }

  haptic::federation::Participant participant_;
  haptic::federation::ToolPublisher publisher_;
  haptic::federation::ToolSubscriber subscriber_;
  DdsReceive mode_;
  Received& into_;
  dds_entity_t reader_ = 0;
  dds_entity_t waitset_ = 0;
  std::vector<ToolState> batch_;
};

// --- One site: a sender, a receiver and the 1 kHz loop, then its records to a file.

struct SiteOptions {
  std::string transport;
  int index = -1;
  std::vector<std::string> addresses;
  std::int64_t start_ns = 0;
  double seconds = 3.0;
  int round = 1;
  std::string out;
};

int run_site(const SiteOptions& o) {
  const int sites = static_cast<int>(o.addresses.size());
  const std::int64_t end_ns = o.start_ns + static_cast<std::int64_t>(o.seconds * 1e9);
  const auto periods = static_cast<std::size_t>(o.seconds * 1e9 / static_cast<double>(kPeriodNs)) + 2;

  Received received(sites, o.index, o.start_ns, end_ns, static_cast<std::size_t>(sites) * periods);
  std::unique_ptr<Transport> transport;
  if (o.transport == "udp") {
    transport = std::make_unique<UdpTransport>(o.addresses, o.index);
  } else {
    const DdsReceive mode = o.transport == "dds" ? DdsReceive::kListener : DdsReceive::kWaitset;
    transport = std::make_unique<DdsTransport>(o.addresses, o.index, mode, received);
  }

  // Sends more than 2 ms after the one before: the sender's own lateness (this host's scheduling),
  // which the receivers see as staleness whatever the transport.
  std::uint64_t sent = 0, send_failed = 0, send_gaps = 0;
  std::thread sender([&] {
    std::int64_t previous = 0;
    ToolState tool = tool_of(o.index, sites);
    // Publishes from now (discovery meets a live writer). Sites' loops are not synchronized: each
    // site's grid is offset by index/sites of a period, spread evenly (no burst of every site's
    // sample at once; up to (sites - 1)/sites of a period between sites' newest samples).
    const std::int64_t origin = o.start_ns + o.index * kPeriodNs / sites;
    std::int64_t next = origin - ((origin - now_ns()) / kPeriodNs) * kPeriodNs;
    while (next < end_ns) {
      sleep_until_ns(next);
      const std::int64_t t = now_ns();
      tool.tick++;
      tool.time_ns = t;
      const bool ok = transport->send(tool);
      if (t >= o.start_ns && t < end_ns) {
        ++sent;
        if (!ok) ++send_failed;
        if (previous >= o.start_ns && t - previous > kStaleLimitNs) ++send_gaps;
      }
      previous = t;
      next += kPeriodNs;
      while (next <= now_ns() - kPeriodNs) next += kPeriodNs;  // overran: the next period, no burst
    }
  });

  std::thread receiver([&] {
    while (now_ns() < end_ns + kDrainNs) transport->receive(received);
  });

  sleep_until_ns(o.start_ns);
  const std::string matched_at_start = transport->matched();
  const std::int64_t cpu_start_ns = process_cpu_ns();

  // The loop: each period, the newest sample in hand per remote site against the newest of all.
  std::vector<std::int64_t> staleness_ns;
  staleness_ns.reserve(periods);
  std::uint64_t loop_periods = 0, missing_periods = 0;
  for (std::int64_t next = o.start_ns; next < end_ns; next += kPeriodNs) {
    sleep_until_ns(next);
    std::int64_t newest_all = 0, oldest_in_hand = 0;
    int heard = 0;
    for (int s = 0; s < sites; ++s) {
      if (s == o.index) continue;
      const std::int64_t t = received.newest(s);
      if (t == 0) continue;
      newest_all = heard == 0 ? t : std::max(newest_all, t);
      oldest_in_hand = heard == 0 ? t : std::min(oldest_in_hand, t);
      ++heard;
    }
    ++loop_periods;
    if (heard < sites - 1) ++missing_periods;
    if (heard > 0) staleness_ns.push_back(newest_all - oldest_in_hand);
    while (next + kPeriodNs <= now_ns() - kPeriodNs) next += kPeriodNs;  // overran: skip, no burst
  }
  const std::int64_t cpu_ns = process_cpu_ns() - cpu_start_ns;
  sender.join();
  receiver.join();
  // No more deliveries: a listener's come on Cyclone's thread until the participant is closed.
  transport.reset();

  std::FILE* file = std::fopen(o.out.c_str(), "w");
  if (file == nullptr) fail("cannot write " + o.out);
  std::fprintf(file, "config %d %s %d %d %.3f\n", o.round, o.transport.c_str(), sites, o.index, o.seconds);
  std::fprintf(file, "sent %llu %llu %llu\n", static_cast<unsigned long long>(sent),
               static_cast<unsigned long long>(send_failed), static_cast<unsigned long long>(send_gaps));
  if (!matched_at_start.empty()) std::fprintf(file, "matched %s\n", matched_at_start.c_str());
  std::fprintf(file, "cpu %lld\n", static_cast<long long>(cpu_ns));
  std::uint8_t sample[2048];
  std::fprintf(file, "bytes %zu\n", encode(tool_of(o.index, sites), sample, sizeof sample));
  for (int s = 0; s < sites; ++s) {
    if (s != o.index) std::fprintf(file, "received %d %llu\n", s, static_cast<unsigned long long>(received.received(s)));
  }
  std::fprintf(file, "loop %llu %llu\n", static_cast<unsigned long long>(loop_periods),
               static_cast<unsigned long long>(missing_periods));
  std::fprintf(file, "foreign %llu\n", static_cast<unsigned long long>(received.foreign()));
  for (const std::int64_t v : received.latency_ns()) std::fprintf(file, "L %lld\n", static_cast<long long>(v));
  for (const std::int64_t v : staleness_ns) std::fprintf(file, "S %lld\n", static_cast<long long>(v));
  const bool written = std::fclose(file) == 0;
  return written ? 0 : 1;
}

// --- Reading the sites' files back: one configuration's figures.

struct Configuration {
  int round = 0;
  std::string transport;
  int sites = 0;
  double seconds = 0;
  int files = 0;
  std::uint64_t sent = 0, send_failed = 0, send_gaps = 0, received = 0, foreign = 0;
  std::uint64_t loop_periods = 0, missing_periods = 0, silent_streams = 0;
  std::int64_t cpu_ns = 0;  // all sites' processes over the window
  std::size_t bytes = 0;    // a sample's CDR (the UDP datagram; DDS adds its RTPS headers)
  std::vector<std::int64_t> latency_ns, staleness_ns;
  std::vector<std::string> unmatched;  // "site-3: 5 readers 6 writers"
};

double quantile_us(const std::vector<std::int64_t>& sorted, double q) {
  if (sorted.empty()) return 0.0;
  return static_cast<double>(sorted[static_cast<std::size_t>(q * static_cast<double>(sorted.size() - 1))]) / 1e3;
}

Configuration read_configuration(const std::string& dir) {
  Configuration c;
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.path().extension() == ".txt") files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  for (const auto& path : files) {
    std::ifstream in(path);
    std::string line;
    int index = -1;
    while (std::getline(in, line)) {
      std::istringstream words(line);
      std::string key;
      words >> key;
      if (key == "L" || key == "S") {
        std::int64_t v = 0;
        words >> v;
        (key == "L" ? c.latency_ns : c.staleness_ns).push_back(v);
      } else if (key == "config") {
        words >> c.round >> c.transport >> c.sites >> index >> c.seconds;
        ++c.files;
      } else if (key == "sent") {
        std::uint64_t n = 0, failed = 0, gaps = 0;
        words >> n >> failed >> gaps;
        c.sent += n;
        c.send_failed += failed;
        c.send_gaps += gaps;
      } else if (key == "matched") {
        // Each site's reader and writer match the other sites' and its own.
        std::uint32_t readers = 0, writers = 0;
        words >> readers >> writers;
        if (readers < static_cast<std::uint32_t>(c.sites) || writers < static_cast<std::uint32_t>(c.sites)) {
          c.unmatched.push_back(site_name(index) + ": " + std::to_string(readers) + " readers, " +
                                std::to_string(writers) + " writers");
        }
      } else if (key == "received") {
        int from = 0;
        std::uint64_t n = 0;
        words >> from >> n;
        c.received += n;
        if (n == 0) ++c.silent_streams;
      } else if (key == "loop") {
        std::uint64_t n = 0, missing = 0;
        words >> n >> missing;
        c.loop_periods += n;
        c.missing_periods += missing;
      } else if (key == "bytes") {
        words >> c.bytes;
      } else if (key == "cpu") {
        std::int64_t n = 0;
        words >> n;
        c.cpu_ns += n;
      } else if (key == "foreign") {
        std::uint64_t n = 0;
        words >> n;
        c.foreign += n;
      }
    }
  }
  if (c.files == 0) fail("no site files in " + dir);
  std::sort(c.latency_ns.begin(), c.latency_ns.end());
  std::sort(c.staleness_ns.begin(), c.staleness_ns.end());
  return c;
}

std::uint64_t stale_periods(const Configuration& c) {
  return static_cast<std::uint64_t>(
      c.staleness_ns.end() - std::upper_bound(c.staleness_ns.begin(), c.staleness_ns.end(), kStaleLimitNs));
}

int streams(const Configuration& c) { return c.sites * (c.sites - 1); }

/// What arrived of what was sent, in percent (each sample sent goes to sites - 1 receivers).
double received_percent(const Configuration& c) {
  const double expected = static_cast<double>(c.sent) * (c.sites - 1);
  return expected > 0 ? 100.0 * static_cast<double>(c.received) / expected : 0.0;
}

int summary(const std::string& dir) {
  const Configuration c = read_configuration(dir);
  std::printf("federation_latency: round %d, %d sites over %s: %zu samples, p50 %.0f us, p99 %.0f us, max %.0f us, "
              "%.1f%% received, %llu of %zu loop periods > 2 ms stale\n",
              c.round, c.sites, c.transport.c_str(), c.latency_ns.size(), quantile_us(c.latency_ns, 0.5),
              quantile_us(c.latency_ns, 0.99), quantile_us(c.latency_ns, 1.0), received_percent(c),
              static_cast<unsigned long long>(stale_periods(c)), c.staleness_ns.size());
  for (const std::string& u : c.unmatched) {
    std::printf("federation_latency:   not all matched at the start: %s (of %d each)\n", u.c_str(), c.sites);
  }
  std::fflush(stdout);
  return c.latency_ns.empty() ? 1 : 0;
}

const char* met(bool ok) { return ok ? "met" : "NOT met"; }

int report(const std::vector<std::string>& dirs) {
  std::vector<Configuration> all;
  for (const std::string& dir : dirs) all.push_back(read_configuration(dir));
  std::printf("\nOne-way latency of the tool topic between network namespaces on one bridge; every site publishes\n"
              "one tool at 1 kHz and receives every other site's; UDP: the same samples (same CDR size), unicast\n"
              "to each peer. Staleness: a 1 kHz loop per site, newest sent time received minus the oldest\n"
              "newest-per-site in hand.\n\n");
  std::printf("%-5s %-11s %5s %5s %7s %8s %7s %7s %7s %8s %8s %9s %12s %12s %8s\n", "round", "via", "sites",
              "bytes", "streams", "samples", "p50_us", "p99_us", "max_us", "rate_Hz", "received", "stale>2ms",
              "stale_p99_us", "stale_max_us", "cpu/site");
  for (const Configuration& c : all) {
    const double rate_hz = static_cast<double>(c.received) / streams(c) / c.seconds;
    char stale[32];
    std::snprintf(stale, sizeof stale, "%.2f%%",
                  c.staleness_ns.empty() ? 0.0
                                         : 100.0 * static_cast<double>(stale_periods(c)) /
                                               static_cast<double>(c.staleness_ns.size()));
    const double cpu_percent = 100.0 * static_cast<double>(c.cpu_ns) / 1e9 / c.seconds / c.files;
    std::printf("%-5d %-11s %5d %5zu %7d %8zu %7.0f %7.0f %7.0f %8.1f %7.1f%% %9s %12.0f %12.0f %7.1f%%\n",
                c.round, c.transport.c_str(), c.sites, c.bytes, streams(c), c.latency_ns.size(), quantile_us(c.latency_ns, 0.5),
                quantile_us(c.latency_ns, 0.99), quantile_us(c.latency_ns, 1.0), rate_hz, received_percent(c), stale,
                quantile_us(c.staleness_ns, 0.99), quantile_us(c.staleness_ns, 1.0), cpu_percent);
  }
  std::printf("\nbytes: a sample's CDR, the UDP datagram's payload (DDS adds its RTPS headers); cpu/site: one\n"
              "site's process (every thread) over the window, in %% of one core; all sites share this host's cores.\n");
  std::printf("\nDDS against the UDP floor of the same round and size (targets: p50 <= %.0fx, p99 <= %.0fx; no sample\n"
              "in hand more than 2 ms older than the newest; with 2 sites one remote site is in hand, so 0 by\n"
              "construction):\n",
              kTargetP50Ratio, kTargetP99Ratio);
  int status = 0;
  for (const Configuration& dds : all) {
    if (dds.transport == "udp") continue;
    const auto floor = std::find_if(all.begin(), all.end(), [&](const Configuration& c) {
      return c.transport == "udp" && c.round == dds.round && c.sites == dds.sites;
    });
    if (floor == all.end() || floor->latency_ns.empty() || dds.latency_ns.empty()) {
      std::printf("  round %d, %d sites, %s: no %s samples\n", dds.round, dds.sites, dds.transport.c_str(),
                  dds.latency_ns.empty() ? "DDS" : "UDP");
      status = 1;
      continue;
    }
    const double p50 = quantile_us(dds.latency_ns, 0.5) / quantile_us(floor->latency_ns, 0.5);
    const double p99 = quantile_us(dds.latency_ns, 0.99) / quantile_us(floor->latency_ns, 0.99);
    const std::uint64_t stale = stale_periods(dds);
    std::printf("  round %d, %d sites, %s: p50 %.2fx (%s), p99 %.2fx (%s), %llu of %zu loop periods with a sample "
                "more than 2 ms older than the newest (%s; UDP: %llu)\n",
                dds.round, dds.sites, dds.transport.c_str(), p50, met(p50 <= kTargetP50Ratio), p99, met(p99 <= kTargetP99Ratio),
                static_cast<unsigned long long>(stale), dds.staleness_ns.size(), met(stale == 0),
                static_cast<unsigned long long>(stale_periods(*floor)));
  }
  std::printf("\nSends more than 2 ms after the site's previous one (the sender late: this host's scheduling, seen\n"
              "as staleness by every receiver whatever the transport):");
  for (const Configuration& c : all) {
    std::printf("%sround %d %s %d: %llu", &c == &all.front() ? "\n  " : "; ", c.round, c.transport.c_str(),
                c.sites, static_cast<unsigned long long>(c.send_gaps));
  }
  std::printf("\n");
  for (const Configuration& c : all) {
    if (c.silent_streams > 0 || c.send_failed > 0 || c.missing_periods > 0 || c.foreign > 0) {
      std::printf("  round %d, %d sites over %s: %llu streams received nothing, %llu sends refused, %llu loop periods "
                  "without every site, %llu samples from no known site\n",
                  c.round, c.sites, c.transport.c_str(), static_cast<unsigned long long>(c.silent_streams),
                  static_cast<unsigned long long>(c.send_failed), static_cast<unsigned long long>(c.missing_periods),
                  static_cast<unsigned long long>(c.foreign));
    }
    if (c.silent_streams > 0) status = 1;  // a transport that did not work, not a slow one
  }
  return status;
}

std::vector<std::string> split(const std::string& text, char separator) {
  std::vector<std::string> parts;
  std::string part;
  std::istringstream in(text);
  while (std::getline(in, part, separator)) {
    if (!part.empty()) parts.push_back(part);
  }
  return parts;
}

int usage() {
  std::fprintf(stderr,
               "usage: federation_latency_bench clock\n"
               "       federation_latency_bench site --transport udp|dds|dds-waitset --index I --addresses A0,A1,...\n"
               "                                --start-ns T --seconds S --round R --out FILE\n"
               "       federation_latency_bench summary DIR\n"
               "       federation_latency_bench report DIR...\n");
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) return usage();
  const std::string role = argv[1];
  if (role == "clock") {
    std::printf("%lld\n", static_cast<long long>(now_ns()));
    return 0;
  }
  if (role == "summary" && argc == 3) return summary(argv[2]);
  if (role == "report" && argc >= 3) return report(std::vector<std::string>(argv + 2, argv + argc));
  if (role != "site") return usage();
  SiteOptions o;
  for (int i = 2; i + 1 < argc; i += 2) {
    const std::string key = argv[i], value = argv[i + 1];
    if (key == "--transport") o.transport = value;
    else if (key == "--index") o.index = std::atoi(value.c_str());
    else if (key == "--addresses") o.addresses = split(value, ',');
    else if (key == "--start-ns") o.start_ns = std::atoll(value.c_str());
    else if (key == "--seconds") o.seconds = std::atof(value.c_str());
    else if (key == "--round") o.round = std::atoi(value.c_str());
    else if (key == "--out") o.out = value;
    else return usage();
  }
  if ((argc - 2) % 2 != 0 || (o.transport != "udp" && o.transport != "dds" && o.transport != "dds-waitset") || o.addresses.size() < 2 ||
      o.index < 0 || o.index >= static_cast<int>(o.addresses.size()) || o.start_ns <= 0 || !(o.seconds > 0) ||
      o.out.empty()) {
    return usage();
  }
  try {
    return run_site(o);
  } catch (const std::exception& error) {
    fail(site_name(o.index) + ": " + error.what());
  }
}
