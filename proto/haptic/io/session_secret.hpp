#pragma once
// A session's secret: the control plane's capability for acting as that session. OpenSession
// returns it to the client that opened the session, and to no one else; the client sends it with
// every session-scoped call as binary gRPC metadata. Session ids are handles that anyone may see
// (events, energy reports); without the secret they let no one act.

#include <cstddef>

namespace haptic::io {

/// The metadata key (binary: gRPC base64-encodes "-bin" values on the wire).
inline constexpr char kSessionSecretMetadataKey[] = "haptic-session-secret-bin";
/// Unit: bytes.
inline constexpr std::size_t kSessionSecretSize = 16;

}  // namespace haptic::io
