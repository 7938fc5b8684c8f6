#include "hameritt/cop/tak_sender.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>

namespace hameritt::cop {
namespace {

using Clock = std::chrono::steady_clock;

sockaddr_in address(const TakEndpoint& e) {
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<uint16_t>(e.port));
  inet_pton(AF_INET, e.host.c_str(), &a.sin_addr);
  return a;
}

// A DNS name as RFC 1123 allows it: letters, digits, '-' and '.'.
bool isHostName(const std::string& host) {
  return !host.empty() && host.size() <= 253 && host.front() != '.' && host.front() != '-' &&
         std::all_of(host.begin(), host.end(), [](char c) {
           return std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '-';
         });
}

std::string seconds(double s) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", s);
  return buf;
}

double wallSeconds() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

std::string errnoText(const char* what) { return std::string(what) + ": " + std::strerror(errno); }

}  // namespace

std::string TakEndpoint::url() const {
  const char* scheme = protocol == Protocol::kUdp   ? "udp://"
                       : protocol == Protocol::kTcp ? "tcp://"
                                                    : "ssl://";
  return scheme + host + ":" + std::to_string(port);
}

TakEndpoint parseTakUrl(const std::string& url) {
  const auto fail = [&](const std::string& why) {
    return EndpointError("TAK endpoint '" + url + "': " + why +
                         " (expected udp://A.B.C.D:PORT, tcp://A.B.C.D:PORT, ssl://HOST:PORT or "
                         "udp:// for the multicast default 239.2.3.1:6969)");
  };
  TakEndpoint e;
  std::string rest;
  if (url.rfind("udp", 0) == 0) {
    e.protocol = TakEndpoint::Protocol::kUdp;
  } else if (url.rfind("tcp", 0) == 0) {
    e.protocol = TakEndpoint::Protocol::kTcp;
  } else if (url.rfind("ssl", 0) == 0) {
    e.protocol = TakEndpoint::Protocol::kSsl;
  } else {
    throw fail("unknown scheme");
  }
  if (url.size() == 3) {
    rest.clear();
  } else if (url.compare(3, 3, "://") == 0) {
    rest = url.substr(6);
  } else {
    throw fail("expected '://' after the scheme");
  }
  if (rest.empty()) {
    if (e.stream()) throw fail("a TCP or TLS endpoint needs host:port");
    return e;  // multicast default
  }
  const size_t colon = rest.rfind(':');
  if (colon == std::string::npos) throw fail("missing ':PORT'");
  e.host = rest.substr(0, colon);
  const std::string port = rest.substr(colon + 1);
  if (port.empty() || port.size() > 5 || !std::all_of(port.begin(), port.end(), ::isdigit))
    throw fail("port '" + port + "' is not a number");
  e.port = std::stoi(port);
  if (e.port < 1 || e.port > 65535) throw fail("port " + port + " outside 1..65535");
  in_addr a{};
  if (inet_pton(AF_INET, e.host.c_str(), &a) != 1) {
    if (e.protocol == TakEndpoint::Protocol::kSsl && isHostName(e.host)) {
      e.multicast = false;
      return e;  // resolved at each connect
    }
    throw fail("host '" + e.host + "' is not a dotted IPv4 address" +
               (e.protocol == TakEndpoint::Protocol::kSsl ? " or a DNS name" : ""));
  }
  const uint32_t first = ntohl(a.s_addr) >> 24;
  e.multicast = first >= 224 && first <= 239;
  if (e.multicast && e.stream()) throw fail("a multicast address over TCP");
  return e;
}

TakSender::TakSender(const TakEndpoint& endpoint, const TakSenderConfig& config)
    : endpoint_(endpoint), config_(config) {
  if (config_.queue_capacity == 0) config_.queue_capacity = 1;
  if (endpoint_.protocol == TakEndpoint::Protocol::kSsl) config_.tls.validate();
  thread_ = std::thread(&TakSender::run, this);
}

TakSender::~TakSender() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  thread_.join();
  closeSocket();
}

void TakSender::send(const CotEvent& event) {
  Payload p;
  // A stream that may not get the server's consent to Version 1 keeps the XML as well.
  if (config_.encoding == TakEncoding::kXml || endpoint_.stream()) p.xml = toXml(event);
  if (config_.encoding == TakEncoding::kProtobuf) p.proto = toTakProto(event);
  push(std::move(p));
}

void TakSender::send(std::string xml) { push(Payload{std::move(xml), {}}); }

void TakSender::push(Payload p) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (queue_.size() >= config_.queue_capacity) {
      queue_.pop_front();
      stats_.dropped++;
    }
    queue_.push_back(std::move(p));
    stats_.queued++;
  }
  wake_.notify_one();
}

TakSenderStats TakSender::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stats_;
}

void TakSender::setError(const std::string& e) {
  std::lock_guard<std::mutex> lock(mutex_);
  stats_.last_error = e;
}

void TakSender::fail(const std::string& e) {
  setError(e);
  if (e == logged_) return;
  logged_ = e;
  if (config_.log) config_.log(true, endpoint_.url() + ": " + e);
}

void TakSender::closeSocket() {
  tls_.reset();  // close_notify before the socket closes
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  protobuf_ = false;
  inbound_.clear();
  std::lock_guard<std::mutex> lock(mutex_);
  stats_.connected = false;
  stats_.protobuf = false;
}

bool TakSender::openUdp() {
  fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd_ < 0) return fail(errnoText("socket")), false;
  if (endpoint_.multicast) {
    const unsigned char ttl = static_cast<unsigned char>(std::clamp(config_.multicast_ttl, 0, 255));
    if (::setsockopt(fd_, IPPROTO_IP, IP_MULTICAST_TTL, &ttl, sizeof ttl) != 0) {
      fail(errnoText("IP_MULTICAST_TTL"));
      closeSocket();
      return false;
    }
  }
  std::lock_guard<std::mutex> lock(mutex_);
  stats_.connected = true;
  return true;
}

bool TakSender::connectTcp() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stats_.connect_attempts++;
  }
  sockaddr_in a = address(endpoint_);
  in_addr probe{};
  if (inet_pton(AF_INET, endpoint_.host.c_str(), &probe) != 1) {  // a DNS name (ssl://)
    addrinfo hints{};
    hints.ai_family = AF_INET;
    hints.ai_socktype = SOCK_STREAM;
    addrinfo* found = nullptr;
    const int rc = ::getaddrinfo(endpoint_.host.c_str(), nullptr, &hints, &found);
    if (rc != 0 || !found) {
      fail("cannot resolve '" + endpoint_.host + "': " + ::gai_strerror(rc));
      return false;
    }
    a.sin_addr = reinterpret_cast<const sockaddr_in*>(found->ai_addr)->sin_addr;
    ::freeaddrinfo(found);
  }
  fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd_ < 0) return fail(errnoText("socket")), false;
  if (::connect(fd_, reinterpret_cast<const sockaddr*>(&a), sizeof a) != 0) {
    if (errno != EINPROGRESS) {
      fail(errnoText("connect"));
      closeSocket();
      return false;
    }
    pollfd p{fd_, POLLOUT, 0};
    const int ready = ::poll(&p, 1, static_cast<int>(config_.connect_timeout_s * 1000));
    int err = 0;
    socklen_t len = sizeof err;
    if (ready <= 0) {
      err = ready == 0 ? ETIMEDOUT : errno;
    } else if (::getsockopt(fd_, SOL_SOCKET, SO_ERROR, &err, &len) != 0) {
      err = errno;
    }
    if (err != 0) {
      errno = err;
      fail(errnoText("connect"));
      closeSocket();
      return false;
    }
  }
  return true;
}

bool TakSender::connectStream() {
  const bool ssl = endpoint_.protocol == TakEndpoint::Protocol::kSsl;
  if (ssl && !tls_context_) {  // the credentials, until they load: before any connection
    try {
      tls_context_ = std::make_unique<TakTlsContext>(config_.tls);
    } catch (const TlsConfigError& e) {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        stats_.connect_attempts++;
        stats_.tls_failures++;
      }
      fail(e.what());
      return false;
    }
  }
  const auto t0 = Clock::now();
  if (!connectTcp()) return false;
  std::string session = "plain TCP";
  if (ssl) {
    try {
      tls_ = std::make_unique<TakTlsConnection>(*tls_context_, fd_, endpoint_.host,
                                                config_.connect_timeout_s);
    } catch (const TlsHandshakeError& e) {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        stats_.tls_failures++;
      }
      fail(e.what());
      closeSocket();
      return false;
    }
    session = tls_->description();
    if (!tls_context_->clientSubject().empty())
      session += ", client " + tls_context_->clientSubject();
  }
  const double handshake_s = std::chrono::duration<double>(Clock::now() - t0).count();
  if (config_.encoding == TakEncoding::kProtobuf && !negotiateProtobuf()) {
    closeSocket();
    return false;
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stats_.connected = true;
    stats_.connects++;
    stats_.last_handshake_s = handshake_s;
    stats_.protobuf = protobuf_;
    stats_.last_error.clear();
  }
  logged_.clear();  // the next failure is logged again
  if (config_.log)
    config_.log(false, "connected to " + endpoint_.url() + " (" + session + "; " +
                           (protobuf_ ? "TAK Protocol Version 1" : "CoT XML") + ")");
  return true;
}

bool TakSender::negotiateProtobuf() {
  // Wait for the server's offer, ask for Version 1, wait for its answer.
  const auto deadline =
      Clock::now() + std::chrono::duration_cast<Clock::duration>(
                         std::chrono::duration<double>(config_.connect_timeout_s));
  bool asked = false;
  while (Clock::now() < deadline) {
    if (!drainInput(&inbound_)) return false;
    const TakNegotiation step = scanNegotiation(inbound_);
    if (step == TakNegotiation::kAccepted && asked) {
      protobuf_ = true;
      return true;
    }
    if (step == TakNegotiation::kDenied) {
      fail("the server denied TAK Protocol Version 1: sending CoT XML on this connection");
      return true;
    }
    if (step == TakNegotiation::kOffered && !asked) {
      if (!writeAll(takProtocolRequest(wallSeconds()))) return false;
      asked = true;
    }
    pollfd p{fd_, POLLIN, 0};
    ::poll(&p, 1, 20);
  }
  if (asked) {  // the protocol asks the client to disconnect: the state is indeterminate
    fail("no answer to the TAK Protocol Version 1 request within " +
         seconds(config_.connect_timeout_s) + " s (connect_timeout_s)");
    return false;
  }
  fail("the server offered no TAK Protocol Version 1 within " + seconds(config_.connect_timeout_s) +
       " s: sending CoT XML on this connection");
  return true;
}

bool TakSender::drainInput(std::string* into) {
  std::string got, error;
  if (tls_) {
    if (!tls_->readAvailable(got, error)) return fail(error), false;
  } else {
    char buf[16384];
    while (true) {
      const ssize_t n = ::recv(fd_, buf, sizeof buf, MSG_DONTWAIT);
      if (n > 0) {
        got.append(buf, static_cast<size_t>(n));
        continue;
      }
      if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) break;
      return fail(n == 0 ? "the server closed the connection" : errnoText("recv")), false;
    }
  }
  if (into) *into += got;
  return true;
}

bool TakSender::writeAll(std::string_view data) {
  if (tls_) {
    std::string error;
    if (tls_->write(data, config_.connect_timeout_s, error)) return true;
    fail(error);
    return false;
  }
  size_t done = 0;
  while (done < data.size()) {
    const ssize_t n = ::send(fd_, data.data() + done, data.size() - done, MSG_NOSIGNAL);
    if (n > 0) {
      done += static_cast<size_t>(n);
      continue;
    }
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
      pollfd p{fd_, POLLOUT, 0};
      if (::poll(&p, 1, static_cast<int>(config_.connect_timeout_s * 1000)) > 0) continue;
      errno = ETIMEDOUT;
    }
    fail(errnoText("send"));
    return false;
  }
  return true;
}

bool TakSender::transmit(const Payload& p) {
  const bool proto = config_.encoding == TakEncoding::kProtobuf && !p.proto.empty();
  if (endpoint_.protocol == TakEndpoint::Protocol::kUdp) {
    const std::string mesh = proto ? frameMesh(p.proto) : std::string();
    const std::string& data = proto ? mesh : p.xml;
    const sockaddr_in a = address(endpoint_);
    if (::sendto(fd_, data.data(), data.size(), 0, reinterpret_cast<const sockaddr*>(&a),
                 sizeof a) == static_cast<ssize_t>(data.size()))
      return true;
    fail(errnoText("sendto"));
    return false;
  }
  // What the server sends (pings, other clients' events) is read and dropped: a closed
  // connection shows up here before the event is written into it, and the event waits for the
  // next connection.
  if (!drainInput(nullptr)) return unsent_ = true, false;
  if (protobuf_ && !p.proto.empty()) return writeAll(frameStream(p.proto));
  return writeAll(p.xml);
}

void TakSender::run() {
  const bool tcp = endpoint_.stream();
  double backoff = config_.reconnect_initial_s;
  Clock::time_point next_attempt = Clock::now();
  std::unique_lock<std::mutex> lock(mutex_);
  while (true) {
    wake_.wait(lock, [&] { return stop_ || !queue_.empty(); });
    if (stop_) break;
    if (fd_ < 0) {
      if (Clock::now() < next_attempt) {  // back-off: sleep, but wake up to stop
        wake_.wait_until(lock, next_attempt, [&] { return stop_; });
        continue;
      }
      lock.unlock();
      const bool ok = tcp ? connectStream() : openUdp();
      lock.lock();
      if (!ok) {
        stats_.next_backoff_s = backoff;
        next_attempt =
            Clock::now() + std::chrono::microseconds(static_cast<long long>(backoff * 1e6));
        backoff = std::min(backoff * 2.0, config_.reconnect_max_s);
        continue;
      }
      backoff = config_.reconnect_initial_s;
      stats_.next_backoff_s = 0.0;
    }
    if (queue_.empty()) continue;
    Payload payload = std::move(queue_.front());
    queue_.pop_front();
    lock.unlock();
    unsent_ = false;
    const bool ok = transmit(payload);
    if (!ok && tcp) closeSocket();  // reconnect (after the current back-off) on the next event
    lock.lock();
    if (!ok && tcp) {  // the next connect waits the back-off: a server that closes at once
      stats_.next_backoff_s = backoff;  // is not hammered
      next_attempt =
          Clock::now() + std::chrono::microseconds(static_cast<long long>(backoff * 1e6));
      backoff = std::min(backoff * 2.0, config_.reconnect_max_s);
    }
    if (ok) {
      stats_.sent++;
    } else if (unsent_ && queue_.size() < config_.queue_capacity) {
      queue_.push_front(std::move(payload));  // nothing of it was written
    } else {
      stats_.send_errors++;
    }
  }
}

}  // namespace hameritt::cop
