// net::TlsPump against a real OpenSSL client over loopback TCP: the handshake (ALPN h2, mutual
// TLS), the HTTP/2 preface check, bytes copied both ways under back-pressure, and each way a
// connection ends. The pump runs non-blocking in the test's thread, as the control listener runs
// it; the client runs blocking in another.

#include "net/tls_pump.hpp"

#include <gtest/gtest.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <openssl/err.h>
#include <openssl/ssl.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <thread>

#include "net/tls_server_context.hpp"

namespace haptic::net {
namespace {

const std::string kCerts = TEST_CERTS_DIR;
const std::string kPreface("PRI * HTTP/2.0\r\n\r\nSM\r\n\r\n");

std::string read_file(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  std::stringstream text;
  text << file.rdbuf();
  return text.str();
}

TlsServerMaterial material(bool mutual) {
  return {read_file(kCerts + "/server.pem"), read_file(kCerts + "/server.key"),
          mutual ? read_file(kCerts + "/ca.pem") : std::string()};
}

/// A connected loopback TCP pair: `server` non-blocking (as accept4 gives the listener), `client`
/// blocking.
struct TcpPair {
  int server = -1, client = -1;
  TcpPair() {
    const int listener = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t length = sizeof address;
    ::bind(listener, reinterpret_cast<sockaddr*>(&address), sizeof address);
    ::listen(listener, 1);
    ::getsockname(listener, reinterpret_cast<sockaddr*>(&address), &length);
    client = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    ::connect(client, reinterpret_cast<sockaddr*>(&address), sizeof address);
    server = ::accept4(listener, nullptr, nullptr, SOCK_CLOEXEC | SOCK_NONBLOCK);
    ::close(listener);
    timeval limit{10, 0};  // a client waiting for bytes that never come fails instead of hanging
    ::setsockopt(client, SOL_SOCKET, SO_RCVTIMEO, &limit, sizeof limit);
    ::setsockopt(client, SOL_SOCKET, SO_SNDTIMEO, &limit, sizeof limit);
  }
  ~TcpPair() { if (client >= 0) ::close(client); }
};

/// The client's side, blocking, in its own thread: what it does is `script`.
struct Client {
  SSL_CTX* context = SSL_CTX_new(TLS_client_method());
  SSL* ssl = nullptr;
  std::string failure;

  explicit Client(int fd, bool with_certificate = false, const std::string& alpn = "h2") {
    SSL_CTX_load_verify_locations(context, (kCerts + "/ca.pem").c_str(), nullptr);
    SSL_CTX_set_verify(context, SSL_VERIFY_PEER, nullptr);
    if (with_certificate) {
      SSL_CTX_use_certificate_file(context, (kCerts + "/client.pem").c_str(), SSL_FILETYPE_PEM);
      SSL_CTX_use_PrivateKey_file(context, (kCerts + "/client.key").c_str(), SSL_FILETYPE_PEM);
    }
    std::string wire(1, static_cast<char>(alpn.size()));
    wire += alpn;
    SSL_CTX_set_alpn_protos(context, reinterpret_cast<const unsigned char*>(wire.data()),
                            static_cast<unsigned>(wire.size()));
    ssl = SSL_new(context);
    SSL_set_fd(ssl, fd);
    SSL_set_tlsext_host_name(ssl, "localhost");
  }
  ~Client() {
    SSL_free(ssl);
    SSL_CTX_free(context);
  }
  bool connect() {
    if (SSL_connect(ssl) == 1) return true;
    failure = take_tls_errors("SSL_connect failed");
    return false;
  }
  bool write_all(const std::string& bytes) {
    std::size_t done = 0;
    while (done < bytes.size()) {
      const int n = SSL_write(ssl, bytes.data() + done, static_cast<int>(bytes.size() - done));
      if (n <= 0) return false;
      done += static_cast<std::size_t>(n);
    }
    return true;
  }
  /// Reads exactly `count` bytes, or fewer if the stream ends.
  std::string read(std::size_t count) {
    std::string out;
    char buffer[16384];
    while (out.size() < count) {
      const int n = SSL_read(ssl, buffer, static_cast<int>(std::min(sizeof buffer, count - out.size())));
      if (n <= 0) break;
      out.append(buffer, static_cast<std::size_t>(n));
    }
    return out;
  }
};

/// Drives `pump` with poll() on what it asks for until `done` holds or 10 s pass; `on_app` runs
/// on every pass once the app side is attached (the test's stand-in for gRPC).
bool drive(TlsPump& pump, const std::function<bool()>& done,
           const std::function<void()>& on_app = {}) {
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (std::chrono::steady_clock::now() < give_up) {
    pump.advance();
    if (on_app && pump.stage() == TlsPump::Stage::kOpen) on_app();
    pump.advance();
    if (done()) return true;
    if (pump.stage() == TlsPump::Stage::kClosed) return done();
    const TlsPump::Interest want = pump.interest();
    pollfd fds[2] = {{pump.net_fd(), static_cast<short>((want.net_read ? POLLIN : 0) | (want.net_write ? POLLOUT : 0)), 0},
                     {pump.app_fd(), static_cast<short>((want.app_read ? POLLIN : 0) | (want.app_write ? POLLOUT : 0)), 0}};
    ::poll(fds, pump.app_fd() >= 0 ? 2 : 1, 5);
  }
  return false;
}

/// The pump for `tcp.server` with a fresh context.
struct Served {
  TlsServerContext context;
  TlsPump pump;
  int grpc_end = -1;  // the socket pair's other end, where gRPC would read
  Served(const TcpPair& tcp, bool mutual) : context(material(mutual)), pump(context.new_connection(tcp.server), tcp.server) {}
  ~Served() { if (grpc_end >= 0) ::close(grpc_end); }
  /// Once the preface is in: the socket pair, as the listener makes it.
  void attach() {
    int pair[2];
    ASSERT_EQ(::socketpair(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0, pair), 0);
    pump.attach_app(pair[0]);
    grpc_end = pair[1];
  }
};

TEST(Http2Preface, IsRecognisedWholeInPartOrNot) {
  EXPECT_EQ(check_http2_preface(kPreface), PrefaceCheck::kComplete);
  EXPECT_EQ(check_http2_preface(kPreface + "\x00\x00\x12\x04"), PrefaceCheck::kComplete);
  EXPECT_EQ(check_http2_preface(""), PrefaceCheck::kSoFar);
  EXPECT_EQ(check_http2_preface("PRI * HTTP/2.0\r\n"), PrefaceCheck::kSoFar);
  EXPECT_EQ(check_http2_preface("GET / HTTP/1.1\r\n"), PrefaceCheck::kNotHttp2);
  EXPECT_EQ(check_http2_preface("\x16\x03\x01"), PrefaceCheck::kNotHttp2);  // a TLS ClientHello
  EXPECT_EQ(check_http2_preface("PRI * HTTP/2.1"), PrefaceCheck::kNotHttp2);
}

TEST(TlsPump, HandsOverAfterThePrefaceAndCopiesAMegabyteEachWayIntact) {
  TcpPair tcp;
  Served served(tcp, false);
  std::string payload(1 << 20, '\0');
  for (std::size_t i = 0; i < payload.size(); ++i) payload[i] = static_cast<char>((i * 7919) >> 3);
  std::string echoed;
  std::thread client_thread([&] {
    Client client(tcp.client);
    if (!client.connect()) return;
    // The preface in two pieces: the pump waits for the rest.
    client.write_all(kPreface.substr(0, 10));
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    client.write_all(kPreface.substr(10));
    // An SSL object is not for two threads at once: write a chunk, read its echo, in turn. The
    // chunks are larger than the pump's queues, small enough for every buffer on the way.
    echoed = client.read(0);
    constexpr std::size_t kChunk = 96 * 1024;
    for (std::size_t done = 0; done < payload.size(); done += kChunk) {
      const std::string chunk = payload.substr(done, kChunk);
      if (!client.write_all(chunk)) return;
      echoed += client.read(chunk.size());
    }
    echoed += client.read(kPreface.size());
  });
  ASSERT_TRUE(drive(served.pump, [&] { return served.pump.stage() == TlsPump::Stage::kReadyToServe; }));
  served.attach();
  // gRPC's stand-in echoes everything back, a little at a time, so both queues fill up.
  std::string pending;
  std::size_t echoed_bytes = 0;
  const bool all = drive(
      served.pump, [&] { return echoed_bytes == kPreface.size() + payload.size(); },
      [&] {
        char buffer[3000];
        const ssize_t n = ::recv(served.grpc_end, buffer, sizeof buffer, 0);
        if (n > 0) pending.append(buffer, static_cast<std::size_t>(n));
        if (!pending.empty()) {
          const ssize_t sent = ::send(served.grpc_end, pending.data(), pending.size(), MSG_NOSIGNAL);
          if (sent > 0) {
            pending.erase(0, static_cast<std::size_t>(sent));
            echoed_bytes += static_cast<std::size_t>(sent);
          }
        }
      });
  EXPECT_TRUE(all) << "echoed " << echoed_bytes;
  ::shutdown(tcp.client, SHUT_WR);  // lets the client's reads finish if anything went missing
  client_thread.join();
  EXPECT_EQ(echoed.size(), kPreface.size() + payload.size());
  EXPECT_TRUE(echoed == kPreface + payload) << "the bytes came back changed";
}

TEST(TlsPump, AClientOfferingNoH2IsRefusedInTheHandshake) {
  TcpPair tcp;
  Served served(tcp, false);
  std::thread client_thread([&] {
    Client client(tcp.client, false, "http/1.1");
    client.connect();
  });
  ASSERT_TRUE(drive(served.pump, [&] { return served.pump.stage() == TlsPump::Stage::kClosed; }));
  client_thread.join();
  EXPECT_FALSE(served.pump.handshake_done());
  EXPECT_NE(served.pump.why().find("TLS:"), std::string::npos) << served.pump.why();
}

TEST(TlsPump, MutualTlsRefusesAClientWithoutACertificateAndTakesOneWithIt) {
  {
    TcpPair tcp;
    Served served(tcp, true);
    std::thread client_thread([&] {
      Client client(tcp.client, false);
      if (client.connect()) client.write_all(kPreface);  // TLS 1.3: the refusal comes after
    });
    ASSERT_TRUE(drive(served.pump, [&] { return served.pump.stage() == TlsPump::Stage::kClosed; }));
    client_thread.join();
    EXPECT_FALSE(served.pump.handshake_done());
    EXPECT_NE(served.pump.why().find("certificate"), std::string::npos) << served.pump.why();
  }
  TcpPair tcp;
  Served served(tcp, true);
  std::thread client_thread([&] {
    Client client(tcp.client, true);
    if (client.connect()) client.write_all(kPreface);
  });
  EXPECT_TRUE(drive(served.pump, [&] { return served.pump.stage() == TlsPump::Stage::kReadyToServe; }))
      << served.pump.why();
  client_thread.join();
}

TEST(TlsPump, SomethingOtherThanHttp2AfterTheHandshakeIsClosed) {
  TcpPair tcp;
  Served served(tcp, false);
  std::thread client_thread([&] {
    Client client(tcp.client);
    if (client.connect()) client.write_all("GET / HTTP/1.1\r\nHost: x\r\n\r\n");
  });
  ASSERT_TRUE(drive(served.pump, [&] { return served.pump.stage() == TlsPump::Stage::kClosed; }));
  client_thread.join();
  EXPECT_TRUE(served.pump.handshake_done());
  EXPECT_NE(served.pump.why().find("not an HTTP/2 client"), std::string::npos) << served.pump.why();
}

TEST(TlsPump, PlaintextToATlsServerFailsTheHandshake) {
  TcpPair tcp;
  Served served(tcp, false);
  ASSERT_EQ(::send(tcp.client, kPreface.data(), kPreface.size(), 0), static_cast<ssize_t>(kPreface.size()));
  ASSERT_TRUE(drive(served.pump, [&] { return served.pump.stage() == TlsPump::Stage::kClosed; }));
  EXPECT_FALSE(served.pump.handshake_done());
  EXPECT_NE(served.pump.why().find("TLS:"), std::string::npos) << served.pump.why();
}

TEST(TlsPump, EndsWhenTheClientClosesAndSaysCloseNotifyWhenGrpcCloses) {
  {  // the client goes
    TcpPair tcp;
    Served served(tcp, false);
    std::thread client_thread([&] {
      Client client(tcp.client);
      if (client.connect()) client.write_all(kPreface);
      ::shutdown(tcp.client, SHUT_RDWR);
    });
    ASSERT_TRUE(drive(served.pump, [&] { return served.pump.stage() == TlsPump::Stage::kReadyToServe; }));
    served.attach();
    client_thread.join();
    EXPECT_TRUE(drive(served.pump, [&] { return served.pump.stage() == TlsPump::Stage::kClosed; }));
    // gRPC has the preface, then the end of the stream.
    std::string got(64, '\0');
    const ssize_t n = ::recv(served.grpc_end, got.data(), got.size(), 0);
    ASSERT_EQ(n, static_cast<ssize_t>(kPreface.size()));
  }
  // gRPC goes: its last bytes reach the client, then close_notify (a clean end of the stream).
  TcpPair tcp;
  Served served(tcp, false);
  std::string received;
  int last_error = 0;
  std::thread client_thread([&] {
    Client client(tcp.client);
    if (!client.connect() || !client.write_all(kPreface)) return;
    received = client.read(5);
    char byte;
    const int n = SSL_read(client.ssl, &byte, 1);
    last_error = SSL_get_error(client.ssl, n);
  });
  ASSERT_TRUE(drive(served.pump, [&] { return served.pump.stage() == TlsPump::Stage::kReadyToServe; }));
  served.attach();
  ASSERT_EQ(::send(served.grpc_end, "bye!!", 5, MSG_NOSIGNAL), 5);
  ::close(served.grpc_end);
  served.grpc_end = -1;
  EXPECT_TRUE(drive(served.pump, [&] { return served.pump.stage() == TlsPump::Stage::kClosed; }));
  client_thread.join();
  EXPECT_EQ(received, "bye!!");
  EXPECT_EQ(last_error, SSL_ERROR_ZERO_RETURN);
}

TEST(TlsServerContext, RefusesAKeyThatIsNotTheCertificatesAndNamesEmptyFiles) {
  TlsServerMaterial wrong_key = material(false);
  wrong_key.key_pem = read_file(kCerts + "/client.key");
  try {
    TlsServerContext context(wrong_key);
    ADD_FAILURE() << "accepted a key that is not the certificate's";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("security.tls: the private key does not match the certificate"),
              std::string::npos) << error.what();
  }
  TlsServerMaterial no_cert = material(false);
  no_cert.cert_pem = "not a certificate";
  EXPECT_THROW({ TlsServerContext context(no_cert); }, std::runtime_error);
  TlsServerMaterial no_ca = material(true);
  no_ca.client_ca_pem = "nothing";
  try {
    TlsServerContext context(no_ca);
    ADD_FAILURE() << "accepted a client CA file without a certificate";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("security.tls.client_ca_file"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace haptic::net
