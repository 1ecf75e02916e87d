#include "net/tcp_listen.hpp"

#include <arpa/inet.h>
#include <netdb.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "net/session_registry.hpp"

namespace haptic::net {

std::string host_of_peer(const sockaddr_storage& address, socklen_t length) {
  UdpAddress wrapped;  // the same normalisation as the data plane's (IPv4-mapped -> IPv4)
  wrapped.storage = address;
  wrapped.length = length;
  return host_of(wrapped);
}

ListeningSockets listen_tcp(const std::string& address, const std::string& what,
                            const std::string& field) {
  std::string host = address, service = "0";
  if (!address.empty() && address.front() == '[') {
    const auto end = address.find(']');
    host = address.substr(1, end == std::string::npos ? std::string::npos : end - 1);
    if (end != std::string::npos && end + 1 < address.size() && address[end + 1] == ':') {
      service = address.substr(end + 2);
    }
  } else if (const auto colon = address.rfind(':'); colon != std::string::npos) {
    host = address.substr(0, colon);
    service = address.substr(colon + 1);
  }
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_PASSIVE | AI_NUMERICSERV;
  addrinfo* found = nullptr;
  if (const int rc = ::getaddrinfo(host.empty() ? nullptr : host.c_str(), service.c_str(), &hints, &found);
      rc != 0) {
    throw std::runtime_error(field + " '" + address + "': " + ::gai_strerror(rc));
  }
  ListeningSockets sockets;
  std::string error;
  for (addrinfo* ai = found; ai != nullptr; ai = ai->ai_next) {
    const int fd = ::socket(ai->ai_family, ai->ai_socktype | SOCK_CLOEXEC | SOCK_NONBLOCK, ai->ai_protocol);
    if (fd < 0) {
      error = std::strerror(errno);
      continue;
    }
    const int on = 1;
    ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &on, sizeof on);
    if (ai->ai_family == AF_INET6) ::setsockopt(fd, IPPROTO_IPV6, IPV6_V6ONLY, &on, sizeof on);
    sockaddr_storage where{};
    std::memcpy(&where, ai->ai_addr, ai->ai_addrlen);
    if (sockets.port != 0) {  // every address on the port the first one got
      (where.ss_family == AF_INET6 ? reinterpret_cast<sockaddr_in6*>(&where)->sin6_port
                                   : reinterpret_cast<sockaddr_in*>(&where)->sin_port) = htons(sockets.port);
    }
    if (::bind(fd, reinterpret_cast<sockaddr*>(&where), ai->ai_addrlen) != 0 ||
        ::listen(fd, SOMAXCONN) != 0) {
      error = std::strerror(errno);
      ::close(fd);
      continue;
    }
    sockaddr_storage bound{};
    socklen_t length = sizeof bound;
    ::getsockname(fd, reinterpret_cast<sockaddr*>(&bound), &length);
    sockets.port = ntohs(bound.ss_family == AF_INET6 ? reinterpret_cast<sockaddr_in6*>(&bound)->sin6_port
                                                     : reinterpret_cast<sockaddr_in*>(&bound)->sin_port);
    sockets.fds.push_back(fd);
  }
  ::freeaddrinfo(found);
  if (sockets.fds.empty()) {
    throw std::runtime_error("cannot listen for " + what + " on " + address + ": " +
                             (error.empty() ? "no address" : error));
  }
  return sockets;
}

}  // namespace haptic::net
