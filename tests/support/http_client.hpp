#pragma once
// A plain HTTP/1.1 client for tests of hapticd's HTTP endpoints (metrics, viewer): one connection
// to 127.0.0.1, requests written as given, replies read by their Content-Length (keep-alive or not).

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <string>

namespace haptic::test {

/// A reply split into its parts; status 0 when none came (the server closed without one).
struct HttpReply {
  int status = 0;
  std::string head;  // status line and headers, without the blank line
  std::string body;

  /// The value of header `name` (as the server spells it), or "" when absent.
  std::string header(const std::string& name) const {
    const std::string key = "\r\n" + name + ": ";
    const auto at = head.find(key);
    if (at == std::string::npos) return {};
    const auto from = at + key.size();
    return head.substr(from, head.find("\r\n", from) - from);
  }
};

class HttpConnection {
 public:
  /// Connects to 127.0.0.1:`port` from `source` (another loopback address is another host to
  /// the server; nullptr: the kernel's choice); a reply not complete within 5 s is taken as it is.
  explicit HttpConnection(std::uint16_t port, const char* source = nullptr)
      : fd_(::socket(AF_INET, SOCK_STREAM, 0)) {
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_port = htons(port);
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    timeval timeout{5, 0};
    ::setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
    if (source != nullptr) {
      sockaddr_in from{};
      from.sin_family = AF_INET;
      ::inet_pton(AF_INET, source, &from.sin_addr);
      if (::bind(fd_, reinterpret_cast<sockaddr*>(&from), sizeof from) != 0) return;
    }
    connected_ = ::connect(fd_, reinterpret_cast<sockaddr*>(&address), sizeof address) == 0;
  }
  ~HttpConnection() { ::close(fd_); }
  HttpConnection(const HttpConnection&) = delete;
  HttpConnection& operator=(const HttpConnection&) = delete;

  bool connected() const { return connected_; }

  /// Writes `bytes` as they are (part of a request, say).
  void send(const std::string& bytes) { (void)::send(fd_, bytes.data(), bytes.size(), MSG_NOSIGNAL); }

  /// Reads one reply: its head, then Content-Length bytes of body (none after a HEAD request).
  HttpReply read_reply(bool head_request = false) {
    HttpReply reply;
    std::size_t end = std::string::npos;
    while ((end = buffer_.find("\r\n\r\n")) == std::string::npos && fill()) {
    }
    if (end == std::string::npos) return reply;
    reply.head = buffer_.substr(0, end);
    buffer_.erase(0, end + 4);
    reply.status = std::atoi(reply.head.substr(reply.head.find(' ') + 1).c_str());
    const std::string length = reply.header("Content-Length");
    const std::size_t want = head_request || length.empty() ? 0 : std::stoul(length);
    while (buffer_.size() < want && fill()) {
    }
    reply.body = buffer_.substr(0, want);
    buffer_.erase(0, reply.body.size());
    return reply;
  }

  /// True when the server has closed the connection: nothing more came before the end of the
  /// stream (within the 5 s a read waits).
  bool closed_by_server() {
    char byte = 0;
    return buffer_.empty() && ::recv(fd_, &byte, 1, 0) == 0;
  }

 private:
  bool fill() {
    char chunk[8192];
    const ssize_t got = ::recv(fd_, chunk, sizeof chunk, 0);
    if (got <= 0) return false;
    buffer_.append(chunk, static_cast<std::size_t>(got));
    return true;
  }

  int fd_;
  bool connected_ = false;
  std::string buffer_;
};

/// One request on a connection of its own; `headers` are extra header lines, each ending "\r\n".
inline HttpReply http_request(std::uint16_t port, const std::string& method, const std::string& path,
                              const std::string& headers = {}) {
  HttpConnection connection(port);
  connection.send(method + " " + path + " HTTP/1.1\r\nHost: 127.0.0.1\r\n" + headers + "\r\n");
  return connection.read_reply(method == "HEAD");
}

inline HttpReply http_get(std::uint16_t port, const std::string& path, const std::string& headers = {}) {
  return http_request(port, "GET", path, headers);
}

}  // namespace haptic::test
