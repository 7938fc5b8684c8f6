// TAK endpoints and senders: URL parsing (multicast parsed, never sent to), UDP and TCP on
// loopback, an unreachable TCP server (back-off, no blocking, reconnect), the bounded queue.
// No assertion on the clock: waits end as soon as their condition holds (their limits are only
// there to end a failing test), and "never blocks" is checked on the queue's counters while the
// sender thread is known to sleep. Also run under ThreadSanitizer
// (test/scripts/test_sanitizers_tsan.sh).
#include "hameritt/cop/tak_sender.h"

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <memory>
#include <thread>

namespace hameritt::cop {
namespace {

using Clock = std::chrono::steady_clock;

// A loopback socket bound to a free port.
struct LoopbackSocket {
  int fd = -1;
  int port = 0;
  explicit LoopbackSocket(int type) {
    fd = ::socket(AF_INET, type, 0);
    int one = 1;
    ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a);
    socklen_t len = sizeof a;
    ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
    port = ntohs(a.sin_port);
  }
  ~LoopbackSocket() {
    if (fd >= 0) ::close(fd);
  }
  std::string receive(int fd_in, int timeout_ms) const {
    pollfd p{fd_in, POLLIN, 0};
    if (::poll(&p, 1, timeout_ms) <= 0) return "";
    char buf[65536];
    const ssize_t n = ::recv(fd_in, buf, sizeof buf, 0);
    return n > 0 ? std::string(buf, static_cast<size_t>(n)) : "";
  }
};

// A port nothing listens on: bound, then closed.
int closedPort() {
  LoopbackSocket s(SOCK_STREAM);
  return s.port;
}

template <class F>
bool waitFor(F f, double seconds) {
  const auto end = Clock::now() + std::chrono::duration<double>(seconds);
  while (Clock::now() < end) {
    if (f()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return f();
}

TEST(TakEndpoint, ParsesUnicastMulticastAndTcpUrls) {
  const TakEndpoint def = parseTakUrl("udp://");
  EXPECT_EQ(def.host, "239.2.3.1");
  EXPECT_EQ(def.port, 6969);
  EXPECT_TRUE(def.multicast);
  EXPECT_TRUE(parseTakUrl("udp").multicast);
  const TakEndpoint m = parseTakUrl("udp://239.2.3.1:6969");
  EXPECT_TRUE(m.multicast);
  EXPECT_EQ(m.url(), "udp://239.2.3.1:6969");
  const TakEndpoint u = parseTakUrl("udp://127.0.0.1:4242");
  EXPECT_FALSE(u.multicast);
  EXPECT_EQ(u.port, 4242);
  const TakEndpoint t = parseTakUrl("tcp://10.1.2.3:8087");
  EXPECT_EQ(t.protocol, TakEndpoint::Protocol::kTcp);
  EXPECT_EQ(t.host, "10.1.2.3");
  EXPECT_FALSE(t.multicast);
  const TakEndpoint s = parseTakUrl("ssl://tak.example.org:8089");  // TLS: a DNS name too
  EXPECT_EQ(s.protocol, TakEndpoint::Protocol::kSsl);
  EXPECT_EQ(s.url(), "ssl://tak.example.org:8089");
  EXPECT_TRUE(s.stream());
  EXPECT_EQ(parseTakUrl("ssl://10.0.0.5:8089").host, "10.0.0.5");
}

TEST(TakEndpoint, RejectsMalformedUrlsNamingThem) {
  for (const char* bad :
       {"http://1.2.3.4:5", "udp://1.2.3.4", "udp://1.2.3.4:0", "udp://1.2.3.4:70000",
        "udp://host.example:5", "tcp://", "tcp", "tcp://239.2.3.1:6969", "udp:/1.2.3.4:5",
        "udp://1.2.3.4:5x", "", "ssl://", "ssl://tak_server:8089", "ssl://tak.example.org",
        "ssl://239.2.3.1:8089", "tcp://tak.example.org:8087"}) {
    try {
      parseTakUrl(bad);
      ADD_FAILURE() << bad;
    } catch (const EndpointError& e) {
      EXPECT_NE(std::string(e.what()).find(std::string("'") + bad + "'"), std::string::npos);
    }
  }
}

TEST(TakSender, SendsEachEventAsOneUdpDatagram) {
  LoopbackSocket rx(SOCK_DGRAM);
  TakSender sender(parseTakUrl("udp://127.0.0.1:" + std::to_string(rx.port)), {});
  sender.send("<event uid=\"a\"/>");
  sender.send("<event uid=\"b\"/>");
  EXPECT_EQ(rx.receive(rx.fd, 60000), "<event uid=\"a\"/>");
  EXPECT_EQ(rx.receive(rx.fd, 60000), "<event uid=\"b\"/>");
  EXPECT_TRUE(waitFor([&] { return sender.stats().sent == 2; }, 60.0));
}

// send() never waits for the network: with the peer dead and the sender thread asleep in a
// one-hour back-off, twenty sends return at once (a send that waited for the peer would never
// return, and the test would end at ctest's timeout) and the bounded queue keeps the newest five,
// counting the fifteen dropped.
TEST(TakSender, SendNeverWaitsForADeadPeer) {
  TakSenderConfig c;
  c.reconnect_initial_s = 3600.0;
  c.queue_capacity = 5;
  TakSender sender(parseTakUrl("tcp://127.0.0.1:" + std::to_string(closedPort())), c);
  sender.send("<event uid=\"first\"/>");
  ASSERT_TRUE(waitFor([&] { return sender.stats().next_backoff_s == 3600.0; }, 60.0));
  for (int i = 0; i < 20; ++i) sender.send("<event uid=\"e" + std::to_string(i) + "\"/>");
  const TakSenderStats s = sender.stats();
  EXPECT_EQ(s.connect_attempts, 1u);  // the thread still sleeps: nothing was taken from the queue
  EXPECT_FALSE(s.connected);
  EXPECT_EQ(s.queued, 21u);
  EXPECT_EQ(s.dropped, 16u);
  EXPECT_EQ(s.sent, 0u);
  EXPECT_EQ(s.send_errors, 0u);
  EXPECT_NE(s.last_error.find("connect"), std::string::npos);
}

TEST(TakSender, UnreachableTcpServerBacksOffThenConnects) {
  const int port = closedPort();
  TakSenderConfig c;
  c.reconnect_initial_s = 0.05;
  c.reconnect_max_s = 0.2;
  c.queue_capacity = 5;
  TakSender sender(parseTakUrl("tcp://127.0.0.1:" + std::to_string(port)), c);
  for (int i = 0; i < 20; ++i) sender.send("<event uid=\"e" + std::to_string(i) + "\"/>");
  ASSERT_TRUE(waitFor([&] { return sender.stats().connect_attempts >= 3; }, 60.0));
  TakSenderStats s = sender.stats();
  EXPECT_FALSE(s.connected);
  EXPECT_EQ(s.dropped, 15u);  // bounded queue: the oldest dropped
  EXPECT_NE(s.last_error.find("connect"), std::string::npos);
  EXPECT_GT(s.next_backoff_s, 0.0);
  EXPECT_LE(s.next_backoff_s, c.reconnect_max_s);

  // The server comes up on that port: the sender connects and streams the queued events.
  LoopbackSocket server(SOCK_STREAM);
  // Rebind to the sender's port.
  ::close(server.fd);
  server.fd = ::socket(AF_INET, SOCK_STREAM, 0);
  int one = 1;
  ::setsockopt(server.fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = htons(static_cast<uint16_t>(port));
  ASSERT_EQ(::bind(server.fd, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
  ASSERT_EQ(::listen(server.fd, 1), 0);
  pollfd p{server.fd, POLLIN, 0};
  ASSERT_GT(::poll(&p, 1, 60000), 0);
  const int conn = ::accept(server.fd, nullptr, nullptr);
  ASSERT_GE(conn, 0);
  std::string stream;
  waitFor(
      [&] {
        stream += server.receive(conn, 50);
        return stream.find("e19") != std::string::npos;
      },
      60.0);
  ::close(conn);
  EXPECT_EQ(stream,
            "<event uid=\"e15\"/><event uid=\"e16\"/><event uid=\"e17\"/>"
            "<event uid=\"e18\"/><event uid=\"e19\"/>");
  EXPECT_TRUE(waitFor([&] { return sender.stats().connects == 1; }, 60.0));
}

// A server that closed the connection: the sender notices before it writes the next event,
// which then goes out on a new connection (not lost, not counted as an error).
TEST(TakSender, EventAfterTheServerClosedGoesOnTheNextConnection) {
  LoopbackSocket server(SOCK_STREAM);
  ASSERT_EQ(::listen(server.fd, 2), 0);
  TakSenderConfig c;
  c.reconnect_initial_s = 0.05;
  TakSender sender(parseTakUrl("tcp://127.0.0.1:" + std::to_string(server.port)), c);
  sender.send("<event uid=\"a\"/>");
  pollfd p{server.fd, POLLIN, 0};
  ASSERT_GT(::poll(&p, 1, 60000), 0);
  int conn = ::accept(server.fd, nullptr, nullptr);
  ASSERT_GE(conn, 0);
  EXPECT_EQ(server.receive(conn, 60000), "<event uid=\"a\"/>");
  ASSERT_TRUE(waitFor([&] { return sender.stats().sent == 1; }, 60.0));
  ::close(conn);  // the server hangs up
  // On loopback the FIN is in the sender's socket when close() returns; the pause is only a
  // margin for that (no time is asserted).
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  sender.send("<event uid=\"b\"/>");
  ASSERT_GT(::poll(&p, 1, 60000), 0);
  conn = ::accept(server.fd, nullptr, nullptr);
  ASSERT_GE(conn, 0);
  EXPECT_EQ(server.receive(conn, 60000), "<event uid=\"b\"/>");
  ::close(conn);
  ASSERT_TRUE(waitFor([&] { return sender.stats().sent == 2; }, 60.0));
  const TakSenderStats s = sender.stats();
  EXPECT_EQ(s.connects, 2u);
  EXPECT_EQ(s.send_errors, 0u);
  EXPECT_EQ(s.dropped, 0u);
  EXPECT_EQ(s.connect_attempts, 2u);
}

// The destructor wakes the thread from its back-off: with a one-hour back-off, a destructor that
// waited it out would hold the test past ctest's timeout.
TEST(TakSender, StopsWhileBackingOff) {
  TakSenderConfig c;
  c.reconnect_initial_s = 3600.0;
  auto sender = std::make_unique<TakSender>(
      parseTakUrl("tcp://127.0.0.1:" + std::to_string(closedPort())), c);
  sender->send("<event/>");
  ASSERT_TRUE(waitFor([&] { return sender->stats().next_backoff_s == 3600.0; }, 60.0));
  sender.reset();
}

}  // namespace
}  // namespace hameritt::cop
