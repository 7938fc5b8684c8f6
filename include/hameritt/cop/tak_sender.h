#pragma once
// Sends CoT events to TAK: UDP (unicast or multicast, the TAK/ATAK "SA" default being
// 239.2.3.1:6969), TCP or TLS (a TAK Server's client port 8089, mutual TLS: tak_tls.h) to a TAK
// server (events streamed back to back), as CoT XML or TAK Protocol Version 1 (tak_proto.h; on
// streams after the server agreed to it, as TAK's protocol negotiation asks). Each sender owns one
// thread and a bounded queue: send() never blocks (the oldest event is dropped, and counted, when
// the queue is full); streams reconnect with exponential back-off up to a cap. A failure is
// reported once per reason through TakSenderConfig::log; TLS never falls back to plaintext.

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>

#include "hameritt/cop/cot.h"
#include "hameritt/cop/tak_proto.h"
#include "hameritt/cop/tak_tls.h"

namespace hameritt::cop {

// A malformed TAK endpoint URL.
class EndpointError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// Where events go.
struct TakEndpoint {
  enum class Protocol { kUdp, kTcp, kSsl };
  Protocol protocol = Protocol::kUdp;
  std::string host = "239.2.3.1";  // dotted IPv4 address; ssl:// also a DNS name
  int port = 6969;
  bool multicast = true;  // host in 224.0.0.0/4 (UDP only)

  std::string url() const;
  bool stream() const { return protocol != Protocol::kUdp; }
};

// Parses "udp://A.B.C.D:PORT", "tcp://A.B.C.D:PORT" or "ssl://HOST:PORT" (HOST a DNS name or a
// dotted IPv4 address); "udp://" alone (or "udp") is the multicast default 239.2.3.1:6969.
// Throws EndpointError naming the URL and what was expected.
TakEndpoint parseTakUrl(const std::string& url);

// Transport settings.
struct TakSenderConfig {
  std::size_t queue_capacity = 1000;
  int multicast_ttl = 1;             // hops; 1 keeps multicast on the local network
  double reconnect_initial_s = 0.5;  // first TCP back-off
  double reconnect_max_s = 30.0;     // back-off cap
  double connect_timeout_s = 2.0;    // TCP connect, TLS handshake, TAK Protocol negotiation
  TakEncoding encoding = TakEncoding::kXml;
  TakTlsConfig tls;  // ssl:// endpoints
  // Called on the sender's thread: each failure once per reason (again after a connect), and
  // each connect. Must not block.
  std::function<void(bool error, const std::string& message)> log;
};

// Counters, readable from any thread.
struct TakSenderStats {
  std::uint64_t queued = 0;
  std::uint64_t sent = 0;
  std::uint64_t dropped = 0;      // oldest events dropped from a full queue
  std::uint64_t send_errors = 0;  // datagrams or streams that failed
  std::uint64_t connect_attempts = 0;
  std::uint64_t connects = 0;
  std::uint64_t tls_failures = 0;  // credentials that did not load, handshakes that failed
  double last_handshake_s = 0.0;   // TCP connect + TLS handshake of the latest connect
  bool protobuf = false;           // events go out as TAK Protocol Version 1 now
  bool connected = false;          // TCP: a live connection; UDP: the socket is open
  double next_backoff_s = 0.0;     // TCP: delay before the next attempt after a failure
  std::string last_error;
};

// One endpoint's sender thread.
class TakSender {
 public:
  TakSender(const TakEndpoint& endpoint, const TakSenderConfig& config);
  ~TakSender();
  TakSender(const TakSender&) = delete;
  TakSender& operator=(const TakSender&) = delete;

  // Queues one event in the configured encoding; never blocks on the network.
  void send(const CotEvent& event);
  // Queues one XML document as it is (every encoding: what XML peers receive).
  void send(std::string xml);
  TakSenderStats stats() const;
  const TakEndpoint& endpoint() const { return endpoint_; }

 private:
  // An event in the encodings the endpoint may need (proto: the unframed TakMessage).
  struct Payload {
    std::string xml, proto;
  };
  void push(Payload p);
  void run();
  bool openUdp();
  bool connectTcp();
  bool connectStream();
  bool negotiateProtobuf();
  bool writeAll(std::string_view data);
  bool drainInput(std::string* into);
  bool transmit(const Payload& p);
  void closeSocket();
  void setError(const std::string& e);
  void fail(const std::string& e);  // setError, and log it unless this reason was logged last

  TakEndpoint endpoint_;
  TakSenderConfig config_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<Payload> queue_;
  TakSenderStats stats_;
  bool stop_ = false;
  int fd_ = -1;
  std::unique_ptr<TakTlsContext> tls_context_;  // loaded at the first connect that finds it
  std::unique_ptr<TakTlsConnection> tls_;
  bool protobuf_ = false;  // the stream speaks TAK Protocol Version 1 (negotiated)
  std::string logged_;     // the reason logged last
  std::string inbound_;    // what the server sent, while negotiating
  bool unsent_ = false;    // the last transmit failed before writing anything
  std::thread thread_;
};

}  // namespace hameritt::cop
