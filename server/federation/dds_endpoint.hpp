#pragma once
// What the federation's topics share over Cyclone's C API: a writer or reader on a topic, made
// and deleted as one (Endpoint), and taking every sample that arrived by loan.

#include <array>
#include <cstddef>
#include <cstdint>
#include <map>
#include <string>

#include <dds/dds.h>

#include "federation/dds_participant.hpp"
#include "federation/dds_qos.hpp"

namespace haptic::federation {

/// How many readers a writer (publication) or writers a reader has matched so far (discovery).
inline std::uint32_t matched_count(dds_entity_t entity, bool publication) {
  if (publication) {
    dds_publication_matched_status_t status{};
    return dds_get_publication_matched_status(entity, &status) == DDS_RETCODE_OK ? status.current_count : 0;
  }
  dds_subscription_matched_status_t status{};
  return dds_get_subscription_matched_status(entity, &status) == DDS_RETCODE_OK ? status.current_count : 0;
}

/// A writer or a reader on one topic of a participant (the topic made for it), deleted with it:
/// every writer and reader of the federation is one (the ROS 2 topics' too), so none leaks when a
/// later one cannot be made.
class Endpoint {
 public:
  enum class Kind { kWriter, kReader };
  /// Takes `qos` (deletes it). Throws std::runtime_error naming the topic and Cyclone's reason.
  Endpoint(const Participant& participant, const dds_topic_descriptor_t* type, const char* topic, Kind kind,
           dds_qos_t* qos);
  ~Endpoint();
  Endpoint(const Endpoint&) = delete;
  Endpoint& operator=(const Endpoint&) = delete;

  dds_entity_t handle() const { return entity_; }
  /// How many readers (of a writer) or writers (of a reader) discovery has matched so far.
  std::uint32_t matched() const { return matched_count(entity_, kind_ == Kind::kWriter); }

 private:
  Kind kind_;
  dds_entity_t topic_ = 0;
  dds_entity_t entity_ = 0;
};

/// The site each writer matched by a reader speaks for (its one partition), looked up once per
/// writer through discovery's data and kept.
class WriterSites {
 public:
  /// The site `writer` (a sample's dds_sample_info_t::publication_handle) speaks for: its
  /// partition, or "" where it is in none or several, or no longer matched.
  const std::string& of(dds_entity_t reader, dds_instance_handle_t writer);

 private:
  std::map<dds_instance_handle_t, std::string> known_;
};

/// Writes one sample; false, with `error` saying why, when Cyclone refused it.
inline bool write_sample(const Endpoint& writer, const void* sample, std::string& error) {
  const dds_return_t done = dds_write(writer.handle(), sample);
  if (done == DDS_RETCODE_OK) return true;
  error = "dds_write: " + dds_error(done);
  return false;
}

/// Points a sample's sequence at `length` elements of `buffer`, which the caller keeps alive until
/// the write returns (Cyclone serializes from it and frees nothing).
template <class Sequence, class Element>
void lend(Sequence& sequence, Element* buffer, std::size_t length, std::size_t maximum) {
  sequence._buffer = buffer;
  sequence._length = static_cast<std::uint32_t>(length);
  sequence._maximum = static_cast<std::uint32_t>(maximum);
  sequence._release = false;
}

/// Takes every sample the reader holds, in batches, by loan (Cyclone owns the samples' sequences
/// until the loan is returned): calls each(const Sample&, const dds_sample_info_t&) per sample,
/// invalid ones (no data: a disposal, a lost writer) included. Returns how many were taken.
template <class Sample, class Each>
std::size_t take_each(dds_entity_t reader, Each&& each) {
  constexpr std::size_t kBatch = 16;
  std::size_t taken = 0;
  for (;;) {
    std::array<void*, kBatch> pointers{};
    std::array<dds_sample_info_t, kBatch> infos{};
    const dds_return_t n = dds_take(reader, pointers.data(), infos.data(), kBatch, kBatch);
    if (n <= 0) break;
    for (dds_return_t i = 0; i < n; ++i) {
      each(*static_cast<const Sample*>(pointers[static_cast<std::size_t>(i)]), infos[static_cast<std::size_t>(i)]);
    }
    dds_return_loan(reader, pointers.data(), n);
    taken += static_cast<std::size_t>(n);
    if (static_cast<std::size_t>(n) < kBatch) break;
  }
  return taken;
}

}  // namespace haptic::federation
