#pragma once
// A DDS domain participant of Eclipse Cyclone DDS (libddsc, Debian's cyclonedds-dev 0.10) for the
// federation of hapticd sites (docs/federation.md): the domain configured from code, not from an
// environment variable, so a site's network is what its hapticd configuration says.
//
// Off the loop: creating and closing participants allocates and may block on the network.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <dds/dds.h>

#include "federation/options.hpp"

namespace haptic::federation {

/// Cyclone's configuration XML for the options (the interface, multicast only without peers, and
/// with security its <Security> element naming the plugins and the files).
std::string cyclone_config(const DomainOptions& options);

/// The folder of Cyclone's security plugins (libdds_security_auth.so, _ac.so, _crypto.so) found
/// when hapticd was configured; "" when none was (the loader's search path is then used).
std::string security_plugin_dir();

/// Whether the plugins' folder is known and holds all three (tests skip without them).
bool security_plugins_available();

/// One participant in a domain configured from DomainOptions; closes it (and everything created
/// under it) when destroyed. Several participants of one domain (local_domain_id, else domain_id) in
/// one process share the domain, configured by the first (its security included), which owns it:
/// destroy that one last.
class Participant {
 public:
  /// Throws std::runtime_error naming the domain and Cyclone's reason when it cannot be created.
  explicit Participant(const DomainOptions& options);
  ~Participant();
  Participant(const Participant&) = delete;
  Participant& operator=(const Participant&) = delete;

  dds_entity_t handle() const { return participant_; }
  const DomainOptions& options() const { return options_; }

 private:
  DomainOptions options_;
  dds_entity_t domain_ = 0;  // ours to delete when we created the domain, else 0
  dds_entity_t participant_ = 0;
};

/// Cyclone's words for a return code ("DDS_RETCODE_TIMEOUT").
std::string dds_error(dds_return_t code);

}  // namespace haptic::federation
