// hameritt_tak_check: checks the link to a TAK endpoint the way the TAK bridge uses it (the same
// sender, TLS settings and encoding): sends N test events and reports what happened.
//   hameritt_tak_check URL [--events N] [--seconds S] [--encoding xml|protobuf]
//     [--client-p12 FILE | --client-cert FILE --client-key FILE] [--trust-store FILE]
//     [--pin-sha256 HEX] [--server-name NAME] [--connect-timeout-s S] [--reconnect-initial-s S]
//     [--lat DEG --lon DEG]
// Passwords come from the environment (never the command line, which `ps` shows):
// HAMERITT_TAK_CLIENT_PASSWORD (client PKCS#12 or encrypted key), HAMERITT_TAK_TRUST_PASSWORD.
// Each failure is printed once with its reason ("tak_check: error: ..."); the sender keeps
// retrying with its back-off until every event is sent or S seconds have passed.
// Exit codes: 0 every event sent, 1 not all sent in time, 2 bad arguments or settings.

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <string>
#include <thread>

#include "hameritt/cop/tak_sender.h"

namespace cop = hameritt::cop;

namespace {

constexpr const char* kUsage =
    "usage: hameritt_tak_check URL [--events N] [--seconds S] [--encoding "
               "xml|protobuf] [--client-p12 FILE | --client-cert FILE --client-key FILE] "
               "[--trust-store FILE] [--pin-sha256 HEX] [--server-name NAME] "
    "[--connect-timeout-s S] [--reconnect-initial-s S] [--lat DEG --lon DEG]\n"
    "Sends N test events to the TAK endpoint URL with the TAK bridge's sender and reports\n"
    "what was sent, what failed and why (docs/howto/connect-tak-server-tls.md).\n"
    "Exit codes: 0 all sent, 1 not all sent, 2 bad arguments or settings.\n";

int usage(const std::string& why) {
  std::fprintf(stderr, "hameritt_tak_check: %s\n%s", why.c_str(), kUsage);
  return 2;
}

double number(const std::string& flag, const std::string& v) {
  char* end = nullptr;
  const double d = std::strtod(v.c_str(), &end);
  if (v.empty() || *end != '\0' || !(d > 0 || flag == "--lat" || flag == "--lon"))
    throw std::invalid_argument(flag + " " + v + ": expected a positive number");
  return d;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc >= 2 && (std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h")) {
    std::fputs(kUsage, stdout);
    return 0;
  }
  if (argc < 2) return usage("missing URL");
  cop::TakSenderConfig config;
  int events = 3;
  double seconds = 10.0, lat = 42.4851, lon = -71.1873;
  cop::TakEndpoint endpoint;
  try {
    endpoint = cop::parseTakUrl(argv[1]);
    for (int i = 2; i < argc; ++i) {
      const std::string flag = argv[i];
      if (i + 1 >= argc) return usage(flag + ": missing value");
      const std::string v = argv[++i];
      if (flag == "--events") {
        events = static_cast<int>(number(flag, v));
      } else if (flag == "--seconds") {
        seconds = number(flag, v);
      } else if (flag == "--encoding") {
        config.encoding = cop::parseTakEncoding(v, "--encoding");
      } else if (flag == "--client-p12") {
        config.tls.client_p12 = v;
      } else if (flag == "--client-cert") {
        config.tls.client_cert = v;
      } else if (flag == "--client-key") {
        config.tls.client_key = v;
      } else if (flag == "--trust-store") {
        config.tls.trust_store = v;
      } else if (flag == "--pin-sha256") {
        config.tls.pin_sha256 = v;
      } else if (flag == "--server-name") {
        config.tls.server_name = v;
      } else if (flag == "--connect-timeout-s") {
        config.connect_timeout_s = number(flag, v);
      } else if (flag == "--reconnect-initial-s") {
        config.reconnect_initial_s = number(flag, v);
      } else if (flag == "--lat") {
        lat = number(flag, v);
      } else if (flag == "--lon") {
        lon = number(flag, v);
      } else {
        return usage("unknown option " + flag);
      }
    }
    if (const char* pw = std::getenv("HAMERITT_TAK_CLIENT_PASSWORD"))
      config.tls.client_password = pw;
    if (const char* pw = std::getenv("HAMERITT_TAK_TRUST_PASSWORD")) config.tls.trust_password = pw;
    config.tls.validate();
  } catch (const std::invalid_argument& e) {
    return usage(e.what());
  }
  if (endpoint.protocol == cop::TakEndpoint::Protocol::kSsl && !config.tls.hasClientCertificate())
    std::fprintf(stderr,
                 "hameritt_tak_check: warning: no client certificate (a TAK Server's TLS input "
                 "refuses the connection)\n");
  config.queue_capacity = static_cast<std::size_t>(events);
  config.reconnect_max_s = std::max(config.reconnect_initial_s, 5.0);
  std::mutex out;
  config.log = [&](bool error, const std::string& message) {
    std::lock_guard<std::mutex> lock(out);
    std::fprintf(error ? stderr : stdout, "tak_check: %s%s\n", error ? "error: " : "",
                 message.c_str());
    std::fflush(error ? stderr : stdout);
  };

  cop::TakSenderStats st;
  {
    cop::TakSender sender(endpoint, config);
    const double now =
        std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
    for (int k = 0; k < events; ++k) {
      cop::CotEvent e;
      e.uid = "hameritt.check." + std::to_string(k);
      e.type = "a-f-G-U-C";
      e.time = e.start = now;
      e.stale = now + 60.0;
      e.point.lat = lat + 1e-4 * k;
      e.point.lon = lon;
      e.point.hae = 40.0;
      e.point.ce = e.point.le = 5.0;
      e.callsign = "HAMERITT-CHECK";
      e.track = std::make_pair(90.0, 1.5);
      e.remarks =
          "hameritt_tak_check event " + std::to_string(k + 1) + " of " + std::to_string(events);
      sender.send(e);
    }
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (std::chrono::steady_clock::now() < end &&
           sender.stats().sent < static_cast<std::uint64_t>(events))
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    st = sender.stats();
  }
  std::lock_guard<std::mutex> lock(out);
  std::printf(
      "tak_check: %s: %llu of %d events sent (%s), %llu connects of %llu attempts, %llu TLS "
      "failures, %llu send errors, %llu dropped, last connect+handshake %.1f ms\n",
      endpoint.url().c_str(), static_cast<unsigned long long>(st.sent), events,
      st.sent == 0 ? "none" : (st.protobuf ? "TAK Protocol Version 1" : "CoT XML"),
      static_cast<unsigned long long>(st.connects),
      static_cast<unsigned long long>(st.connect_attempts),
      static_cast<unsigned long long>(st.tls_failures),
      static_cast<unsigned long long>(st.send_errors), static_cast<unsigned long long>(st.dropped),
      st.last_handshake_s * 1e3);
  return st.sent == static_cast<std::uint64_t>(events) ? 0 : 1;
}
