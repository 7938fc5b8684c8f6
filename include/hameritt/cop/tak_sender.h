#pragma once
// Sends CoT events to TAK: UDP (unicast or multicast, the TAK/ATAK "SA" default being
// 239.2.3.1:6969) or TCP to a TAK server (events streamed back to back). Each sender owns one
// thread and a bounded queue: send() never blocks (the oldest event is dropped, and counted, when
// the queue is full); TCP reconnects with exponential back-off up to a cap.

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>

namespace hameritt::cop {

// A malformed TAK endpoint URL.
class EndpointError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// Where events go.
struct TakEndpoint {
  enum class Protocol { kUdp, kTcp };
  Protocol protocol = Protocol::kUdp;
  std::string host = "239.2.3.1";  // dotted IPv4 address (no name lookup)
  int port = 6969;
  bool multicast = true;  // host in 224.0.0.0/4 (UDP only)

  std::string url() const;
};

// Parses "udp://A.B.C.D:PORT" or "tcp://A.B.C.D:PORT"; "udp://" alone (or "udp") is the
// multicast default 239.2.3.1:6969. Throws EndpointError naming the URL and what was expected.
TakEndpoint parseTakUrl(const std::string& url);

// Transport settings.
struct TakSenderConfig {
  std::size_t queue_capacity = 1000;
  int multicast_ttl = 1;             // hops; 1 keeps multicast on the local network
  double reconnect_initial_s = 0.5;  // first TCP back-off
  double reconnect_max_s = 30.0;     // back-off cap
  double connect_timeout_s = 2.0;
};

// Counters, readable from any thread.
struct TakSenderStats {
  std::uint64_t queued = 0;
  std::uint64_t sent = 0;
  std::uint64_t dropped = 0;      // oldest events dropped from a full queue
  std::uint64_t send_errors = 0;  // datagrams or streams that failed
  std::uint64_t connect_attempts = 0;
  std::uint64_t connects = 0;
  bool connected = false;       // TCP: a live connection; UDP: the socket is open
  double next_backoff_s = 0.0;  // TCP: delay before the next attempt after a failure
  std::string last_error;
};

// One endpoint's sender thread.
class TakSender {
 public:
  TakSender(const TakEndpoint& endpoint, const TakSenderConfig& config);
  ~TakSender();
  TakSender(const TakSender&) = delete;
  TakSender& operator=(const TakSender&) = delete;

  // Queues one event (an XML document); never blocks on the network.
  void send(std::string xml);
  TakSenderStats stats() const;
  const TakEndpoint& endpoint() const { return endpoint_; }

 private:
  void run();
  bool openUdp();
  bool connectTcp();
  bool transmit(const std::string& xml);
  void closeSocket();
  void setError(const std::string& e);

  TakEndpoint endpoint_;
  TakSenderConfig config_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<std::string> queue_;
  TakSenderStats stats_;
  bool stop_ = false;
  int fd_ = -1;
  std::thread thread_;
};

}  // namespace hameritt::cop
