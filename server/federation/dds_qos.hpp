#pragma once
// Every QoS the federation's DDS endpoints use, by name, in one place: each returns a new
// dds_qos_t that the caller hands to an Endpoint (which deletes it). docs/federation.md says which
// topic takes which.

#include <chrono>
#include <string>

#include <dds/dds.h>

namespace haptic::federation {

/// State worth only its newest sample (tools, shared masses' copies, a ROS 2 node's wrench): best
/// effort, keep last one, volatile. A best-effort reader matches a reliable or best-effort writer.
dds_qos_t* newest_only_qos();

/// The shared scene's items: reliable, transient-local (a site that joins late gets every item's
/// last state), keep last one per item, liveliness automatic with `lease` (a site that stops or
/// leaves the network has its items removed once the lease runs out).
dds_qos_t* shared_item_qos(std::chrono::milliseconds lease);

/// A tool on ROS 2 topics: reliable, so that a ROS 2 subscriber with the default profile (reliable,
/// keep last 10) matches as well as one with the sensor-data profile (best effort); keep last one,
/// so that the writer never waits on a slow reader (history replaces what was not yet taken);
/// volatile, as ROS 2's default.
dds_qos_t* ros2_publisher_qos();

/// A site speaks for itself only: each site's writers on the federation's topics are in one
/// partition, its name, and its readers in every partition ("*"). Under DDS Security a site's
/// permissions let it publish in its own partition alone (scripts/federation-certs), and every
/// reader checks a remote writer's partitions against the writer's permissions before it matches,
/// so the partition a sample comes through is vouched for by its writer's identity; the relay and
/// the replicator refuse a sample that names another site. Both take `qos` and return it.
dds_qos_t* in_site_partition(dds_qos_t* qos, const std::string& site);
/// ... and a site's readers read the other sites alone: Cyclone's ignore-local
/// (DDS_IGNORELOCAL_PARTICIPANT) keeps the writers of the reader's own participant, the site's
/// own, from matching, so nothing a site publishes comes back to it.
dds_qos_t* from_other_sites(dds_qos_t* qos);

}  // namespace haptic::federation
