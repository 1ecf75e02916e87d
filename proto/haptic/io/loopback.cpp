#include "haptic/io/loopback.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <strings.h>

#include <string>

namespace haptic::io {

bool is_loopback_address(const sockaddr* address) {
  if (address == nullptr) return false;
  if (address->sa_family == AF_INET) {
    const auto* v4 = reinterpret_cast<const sockaddr_in*>(address);
    return (ntohl(v4->sin_addr.s_addr) >> 24) == 127;
  }
  if (address->sa_family == AF_INET6) {
    const in6_addr& v6 = reinterpret_cast<const sockaddr_in6*>(address)->sin6_addr;
    if (IN6_IS_ADDR_LOOPBACK(&v6)) return true;
    return IN6_IS_ADDR_V4MAPPED(&v6) && v6.s6_addr[12] == 127;
  }
  return false;
}

bool is_loopback_literal(std::string_view host) {
  if (host.size() >= 2 && host.front() == '[' && host.back() == ']') host = host.substr(1, host.size() - 2);
  const std::string text(host);
  if (::strcasecmp(text.c_str(), "localhost") == 0) return true;
  sockaddr_in v4{};
  v4.sin_family = AF_INET;
  // inet_pton takes only the dotted quad (not "127.1" or "0x7f.1"): a resolver's other forms
  // are names here.
  if (::inet_pton(AF_INET, text.c_str(), &v4.sin_addr) == 1) {
    return is_loopback_address(reinterpret_cast<const sockaddr*>(&v4));
  }
  sockaddr_in6 v6{};
  v6.sin6_family = AF_INET6;
  if (::inet_pton(AF_INET6, text.c_str(), &v6.sin6_addr) == 1) {
    return is_loopback_address(reinterpret_cast<const sockaddr*>(&v6));
  }
  return false;
}

}  // namespace haptic::io
