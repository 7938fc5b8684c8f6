#include "hameritt/cop/tak_sender.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
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

std::string errnoText(const char* what) { return std::string(what) + ": " + std::strerror(errno); }

}  // namespace

std::string TakEndpoint::url() const {
  return std::string(protocol == Protocol::kUdp ? "udp://" : "tcp://") + host + ":" +
         std::to_string(port);
}

TakEndpoint parseTakUrl(const std::string& url) {
  const auto fail = [&](const std::string& why) {
    return EndpointError("TAK endpoint '" + url + "': " + why +
                         " (expected udp://A.B.C.D:PORT, tcp://A.B.C.D:PORT or udp:// for the "
                         "multicast default 239.2.3.1:6969)");
  };
  TakEndpoint e;
  std::string rest;
  if (url.rfind("udp", 0) == 0) {
    e.protocol = TakEndpoint::Protocol::kUdp;
  } else if (url.rfind("tcp", 0) == 0) {
    e.protocol = TakEndpoint::Protocol::kTcp;
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
    if (e.protocol == TakEndpoint::Protocol::kTcp) throw fail("a TCP endpoint needs host:port");
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
  if (inet_pton(AF_INET, e.host.c_str(), &a) != 1)
    throw fail("host '" + e.host + "' is not a dotted IPv4 address");
  const uint32_t first = ntohl(a.s_addr) >> 24;
  e.multicast = first >= 224 && first <= 239;
  if (e.multicast && e.protocol == TakEndpoint::Protocol::kTcp)
    throw fail("a multicast address over TCP");
  return e;
}

TakSender::TakSender(const TakEndpoint& endpoint, const TakSenderConfig& config)
    : endpoint_(endpoint), config_(config) {
  if (config_.queue_capacity == 0) config_.queue_capacity = 1;
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

void TakSender::send(std::string xml) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (queue_.size() >= config_.queue_capacity) {
      queue_.pop_front();
      stats_.dropped++;
    }
    queue_.push_back(std::move(xml));
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

void TakSender::closeSocket() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  std::lock_guard<std::mutex> lock(mutex_);
  stats_.connected = false;
}

bool TakSender::openUdp() {
  fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd_ < 0) return setError(errnoText("socket")), false;
  if (endpoint_.multicast) {
    const unsigned char ttl = static_cast<unsigned char>(std::clamp(config_.multicast_ttl, 0, 255));
    if (::setsockopt(fd_, IPPROTO_IP, IP_MULTICAST_TTL, &ttl, sizeof ttl) != 0) {
      setError(errnoText("IP_MULTICAST_TTL"));
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
  fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd_ < 0) return setError(errnoText("socket")), false;
  const sockaddr_in a = address(endpoint_);
  if (::connect(fd_, reinterpret_cast<const sockaddr*>(&a), sizeof a) != 0) {
    if (errno != EINPROGRESS) {
      setError(errnoText("connect"));
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
      setError(errnoText("connect"));
      closeSocket();
      return false;
    }
  }
  std::lock_guard<std::mutex> lock(mutex_);
  stats_.connected = true;
  stats_.connects++;
  stats_.last_error.clear();
  return true;
}

bool TakSender::transmit(const std::string& xml) {
  if (endpoint_.protocol == TakEndpoint::Protocol::kUdp) {
    const sockaddr_in a = address(endpoint_);
    if (::sendto(fd_, xml.data(), xml.size(), 0, reinterpret_cast<const sockaddr*>(&a), sizeof a) ==
        static_cast<ssize_t>(xml.size()))
      return true;
    setError(errnoText("sendto"));
    return false;
  }
  size_t done = 0;
  while (done < xml.size()) {
    const ssize_t n = ::send(fd_, xml.data() + done, xml.size() - done, MSG_NOSIGNAL);
    if (n > 0) {
      done += static_cast<size_t>(n);
      continue;
    }
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
      pollfd p{fd_, POLLOUT, 0};
      if (::poll(&p, 1, static_cast<int>(config_.connect_timeout_s * 1000)) > 0) continue;
      errno = ETIMEDOUT;
    }
    setError(errnoText("send"));
    return false;
  }
  return true;
}

void TakSender::run() {
  const bool tcp = endpoint_.protocol == TakEndpoint::Protocol::kTcp;
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
      const bool ok = tcp ? connectTcp() : openUdp();
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
    std::string xml = std::move(queue_.front());
    queue_.pop_front();
    lock.unlock();
    const bool ok = transmit(xml);
    if (!ok && tcp) closeSocket();  // reconnect (after the current back-off) on the next event
    lock.lock();
    if (ok) {
      stats_.sent++;
    } else {
      stats_.send_errors++;
    }
  }
}

}  // namespace hameritt::cop
