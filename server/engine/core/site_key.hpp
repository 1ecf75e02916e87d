#pragma once
// A federation site as the scene and the loop know it (docs/federation.md): the one type for the
// site an item or a shared mass came from, the site a mass copy or a coupling belongs to, and,
// with a port, the key of another site's tool. The federation names sites by their names; the
// scene and the loop, which must not allocate, by these keys: the FNV-1a (64 bit) of the name, the
// same at every site.

#include <cstdint>
#include <string_view>

namespace haptic::engine {

struct SiteKey {
  std::uint64_t value = 0;  // 0: no site (an empty slot; for an item's origin, this site)

  explicit operator bool() const { return value != 0; }
  friend bool operator==(const SiteKey&, const SiteKey&) = default;
};

/// FNV-1a (64 bit) over `bytes`, continuing from `hash` (the offset basis to start).
inline constexpr std::uint64_t kFnvOffsetBasis = 14695981039346656037ull;
inline constexpr std::uint64_t fnv1a(std::string_view bytes, std::uint64_t hash = kFnvOffsetBasis) {
  for (const char c : bytes) {
    hash ^= static_cast<unsigned char>(c);
    hash *= 1099511628211ull;
  }
  return hash;
}

/// The key of the site named `site`: never 0.
inline constexpr SiteKey site_key(std::string_view site) {
  const std::uint64_t hash = fnv1a(site);
  return SiteKey{hash != 0 ? hash : 1};
}

/// The key of another site's tool, `port` of `site`: FNV-1a over the name, a 0 byte and the port's
/// four bytes (little end first); the same at every site, never 0.
inline constexpr std::uint64_t tool_key(std::string_view site, std::uint32_t port) {
  const char tail[5] = {0, static_cast<char>(port), static_cast<char>(port >> 8), static_cast<char>(port >> 16),
                        static_cast<char>(port >> 24)};
  const std::uint64_t hash = fnv1a(std::string_view(tail, sizeof tail), fnv1a(site));
  return hash != 0 ? hash : 1;
}

/// A shared mass's key at every site: its origin site's key and its id there (splitmix64's
/// finaliser over the pair: distinct pairs give distinct keys but for a 2^-64 chance). Never 0.
inline constexpr std::uint64_t shared_mass_key(SiteKey origin_site, std::uint64_t origin_id) {
  const std::uint64_t site = origin_site.value;
  std::uint64_t z = site ^ (origin_id + 0x9e3779b97f4a7c15ull + (site << 6) + (site >> 2));
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  z ^= z >> 31;
  return z != 0 ? z : 1;
}

}  // namespace haptic::engine
