#include "net/state_pacer.hpp"

#include <pthread.h>

#include <algorithm>

#include "net/read_back.hpp"

namespace haptic::net {

StatePacer::StatePacer() {
  thread_ = std::thread([this] {
    ::pthread_setname_np(::pthread_self(), "state-pacer");
    run();
  });
}

StatePacer::~StatePacer() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  changed_.notify_all();
  thread_.join();
}

std::chrono::steady_clock::time_point StatePacer::next_on_grid(
    std::chrono::nanoseconds period, std::chrono::steady_clock::time_point now) const {
  const auto since = now - epoch_;
  return epoch_ + (since / period + 1) * period;
}

std::uint64_t StatePacer::add(Stream stream) {
  std::lock_guard lock(mutex_);
  Paced paced;
  paced.id = next_id_++;
  paced.next = next_on_grid(stream.period, std::chrono::steady_clock::now());
  paced.stream = std::move(stream);
  streams_.push_back(std::move(paced));
  changed_.notify_all();
  return streams_.back().id;
}

void StatePacer::remove(std::uint64_t id) {
  // Under the lock: the pacer calls sinks under it too, so none runs after this returns.
  std::lock_guard lock(mutex_);
  std::erase_if(streams_, [id](const Paced& paced) { return paced.id == id; });
}

bool StatePacer::running(std::uint64_t id) const {
  std::lock_guard lock(mutex_);
  const auto found = std::find_if(streams_.begin(), streams_.end(), [id](const Paced& p) { return p.id == id; });
  return found != streams_.end() && !found->ended;
}

void StatePacer::run() {
  std::string datagram(wire::kMaxDatagramSize, '\0');
  std::unique_lock lock(mutex_);
  while (!stopping_) {
    auto wake = std::chrono::steady_clock::time_point::max();
    for (const Paced& paced : streams_) {
      if (!paced.ended) wake = std::min(wake, paced.next);
    }
    if (wake == std::chrono::steady_clock::time_point::max()) {
      changed_.wait(lock);
      continue;
    }
    if (changed_.wait_until(lock, wake) == std::cv_status::no_timeout) continue;  // a change: look again
    const auto now = std::chrono::steady_clock::now();
    for (Paced& paced : streams_) {
      if (paced.ended || paced.next > now) continue;
      // The next point of its grid after now: a stall is not made up for with a burst.
      paced.next = next_on_grid(paced.stream.period, now);
      const runtime::SampleRing& ring = *paced.stream.ring;
      const std::uint64_t newest = ring.newest();
      runtime::TickSample sample;
      if (newest == paced.sent_tick || !ring.read(newest, sample)) continue;
      paced.sent_tick = newest;
      wire::Header header;
      header.session_id = paced.stream.session_id;
      header.sequence = ++paced.sequence;
      header.time_ns = sample.time_ns;
      const std::size_t size = wire::encode_state(
          header, state_payload(sample), paced.stream.key,
          std::span<std::uint8_t>(reinterpret_cast<std::uint8_t*>(datagram.data()), datagram.size()));
      if (!paced.stream.sink(datagram.substr(0, size))) paced.ended = true;
    }
  }
}

}  // namespace haptic::net
