#include "federation/item_topic.hpp"

#include <array>
#include <cstring>
#include <stdexcept>

#include "haptic/dds/federation.h"

namespace haptic::federation {

namespace {

using Sample = haptic_federation_SharedItem;

/// The key of a sample: false where the site's name does not fit.
bool fill_key(Sample& sample, const std::string& site, std::uint64_t item, std::string& error) {
  if (site.empty() || site.size() >= sizeof sample.site) {
    error = "site: 1 to 64 characters, got " + std::to_string(site.size());
    return false;
  }
  std::memcpy(sample.site, site.data(), site.size());
  sample.item = item;
  return true;
}

}  // namespace

ItemPublisher::ItemPublisher(const Participant& participant, const std::string& site)
    : writer_(participant, &haptic_federation_SharedItem_desc, kItemTopic, Endpoint::Kind::kWriter,
              in_site_partition(shared_item_qos(kItemLease), site)) {}

bool ItemPublisher::put(const SharedItemState& item) {
  Sample sample{};
  if (!fill_key(sample, item.site, item.item, error_)) return false;
  if (item.spec.size() > kMaxItemBytes) {
    error_ = "spec: at most " + std::to_string(kMaxItemBytes) + " bytes, got " + std::to_string(item.spec.size());
    return false;
  }
  sample.version = item.version;
  sample.kind = static_cast<std::uint8_t>(item.kind);
  lend(sample.spec, reinterpret_cast<std::uint8_t*>(const_cast<char*>(item.spec.data())), item.spec.size(),
       item.spec.size());
  return write_sample(writer_, &sample, error_);
}

bool ItemPublisher::remove(const std::string& site, std::uint64_t item) {
  Sample sample{};
  if (!fill_key(sample, site, item, error_)) return false;
  const dds_return_t done = dds_dispose(writer_.handle(), &sample);
  if (done != DDS_RETCODE_OK) {
    error_ = "dds_dispose: " + dds_error(done);
    return false;
  }
  return true;
}

std::uint32_t ItemPublisher::matched_readers() const { return writer_.matched(); }

ItemSubscriber::ItemSubscriber(const Participant& participant)
    : reader_(participant, &haptic_federation_SharedItem_desc, kItemTopic, Endpoint::Kind::kReader,
              from_other_sites(shared_item_qos(kItemLease))) {}

std::size_t ItemSubscriber::take(std::vector<SharedItemEvent>& out) {
  std::size_t taken = 0;
  take_each<Sample>(reader_.handle(), [&](const Sample& s, const dds_sample_info_t& info) {
    SharedItemEvent event;
    // An invalid sample (no data) still carries the instance's key.
    event.state.site.assign(s.site, strnlen(s.site, sizeof s.site));
    event.state.item = s.item;
    if (info.valid_data || info.instance_state == DDS_IST_NOT_ALIVE_DISPOSED) {
      event.writer_site = writers_.of(reader_.handle(), info.publication_handle);
    }
    if (info.valid_data) {
      if (s.kind > 1 || s.spec._length > kMaxItemBytes) return;  // not ours to read
      event.what = SharedItemEvent::What::kPut;
      event.state.version = s.version;
      event.state.kind = s.kind == 1 ? SharedItemKind::kField : SharedItemKind::kObject;
      event.state.spec.assign(reinterpret_cast<const char*>(s.spec._buffer), s.spec._length);
    } else if (info.instance_state == DDS_IST_NOT_ALIVE_DISPOSED) {
      event.what = SharedItemEvent::What::kRemoved;
    } else if (info.instance_state == DDS_IST_NOT_ALIVE_NO_WRITERS) {
      event.what = SharedItemEvent::What::kLost;
    } else {
      return;
    }
    out.push_back(std::move(event));
    ++taken;
  });
  return taken;
}

std::uint32_t ItemSubscriber::matched_writers() const { return reader_.matched(); }

}  // namespace haptic::federation
