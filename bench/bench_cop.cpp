// COP and CoT throughput: fuses reports of N entities (claims with 3 m noise) into the
// OperationalPicture, then builds the CoT XML events of every track (geodetic conversion
// included) and their TAK Protocol Version 1 encoding, and, separately, sends them as UDP
// datagrams to a loopback port nobody reads and over mutual TLS to a loopback TLS server run here
// (certificates made in memory, 127.0.0.1 only). Prints COP updates (reports) per second,
// observations per second, CoT events built per second, events sent per second (UDP; TLS: until
// the server has read them all) and the TLS connect + handshake time (median of 20).
//
// Usage: bench_cop [entities] [reports]

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <openssl/err.h>
#include <openssl/evp.h>
#include <openssl/pem.h>
#include <openssl/ssl.h>
#include <openssl/x509v3.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "hameritt/cop/cot.h"
#include "hameritt/cop/operational_picture.h"
#include "hameritt/cop/tak_events.h"
#include "hameritt/cop/tak_proto.h"
#include "hameritt/cop/tak_sender.h"
#include "hameritt/cop/tak_tls.h"

namespace cop = hameritt::cop;
using Clock = std::chrono::steady_clock;

namespace {

// A P-256 key and a certificate for CN=`cn` (127.0.0.1), signed by `issuer_key` (itself when
// null), written as PEM files DIR/NAME.pem and DIR/NAME.key.
struct Cert {
  EVP_PKEY* key = nullptr;
  X509* cert = nullptr;
};

Cert makeCert(const std::string& cn, const Cert* issuer, bool ca, const std::string& path) {
  Cert c;
  c.key = EVP_EC_gen("P-256");
  c.cert = X509_new();
  X509_set_version(c.cert, 2);
  ASN1_INTEGER_set(X509_get_serialNumber(c.cert),
                   static_cast<long>(std::hash<std::string>()(cn) & 0x7fffffff));
  X509_gmtime_adj(X509_getm_notBefore(c.cert), -60);
  X509_gmtime_adj(X509_getm_notAfter(c.cert), 86400);
  X509_set_pubkey(c.cert, c.key);
  X509_NAME* name = X509_get_subject_name(c.cert);
  X509_NAME_add_entry_by_txt(name, "CN", MBSTRING_ASC,
                             reinterpret_cast<const unsigned char*>(cn.c_str()), -1, -1, 0);
  X509_set_issuer_name(c.cert, issuer ? X509_get_subject_name(issuer->cert) : name);
  X509V3_CTX v3;
  X509V3_set_ctx(&v3, issuer ? issuer->cert : c.cert, c.cert, nullptr, nullptr, 0);
  for (const char* ext :
       {ca ? "basicConstraints=critical,CA:TRUE" : "subjectAltName=IP:127.0.0.1"}) {
    const std::string kv = ext;
    const size_t eq = kv.find('=');
    X509_EXTENSION* e =
        X509V3_EXT_nconf(nullptr, &v3, kv.substr(0, eq).c_str(), kv.substr(eq + 1).c_str());
    X509_add_ext(c.cert, e, -1);
    X509_EXTENSION_free(e);
  }
  X509_sign(c.cert, issuer ? issuer->key : c.key, EVP_sha256());
  FILE* f = std::fopen((path + ".pem").c_str(), "w");
  PEM_write_X509(f, c.cert);
  std::fclose(f);
  f = std::fopen((path + ".key").c_str(), "w");
  PEM_write_PrivateKey(f, c.key, nullptr, nullptr, 0, nullptr, nullptr);
  std::fclose(f);
  return c;
}

// A TLS server on 127.0.0.1 that requires a client certificate: each connection is read to its
// end on its own thread; `bytes` counts what arrived.
class LoopbackTlsServer {
 public:
  explicit LoopbackTlsServer(const std::string& dir) {
    ctx_ = SSL_CTX_new(TLS_server_method());
    SSL_CTX_use_certificate_file(ctx_, (dir + "/server.pem").c_str(), SSL_FILETYPE_PEM);
    SSL_CTX_use_PrivateKey_file(ctx_, (dir + "/server.key").c_str(), SSL_FILETYPE_PEM);
    SSL_CTX_load_verify_locations(ctx_, (dir + "/ca.pem").c_str(), nullptr);
    SSL_CTX_set_verify(ctx_, SSL_VERIFY_PEER | SSL_VERIFY_FAIL_IF_NO_PEER_CERT, nullptr);
    fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ::bind(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a);
    socklen_t len = sizeof a;
    ::getsockname(fd_, reinterpret_cast<sockaddr*>(&a), &len);
    port = ntohs(a.sin_port);
    ::listen(fd_, 64);
    accept_ = std::thread([this] {
      while (true) {
        const int c = ::accept(fd_, nullptr, nullptr);
        if (c < 0) return;
        readers_.emplace_back([this, c] {
          SSL* ssl = SSL_new(ctx_);
          SSL_set_fd(ssl, c);
          if (SSL_accept(ssl) == 1) {
            char buf[65536];
            int n;
            while ((n = SSL_read(ssl, buf, sizeof buf)) > 0) bytes += static_cast<size_t>(n);
          }
          SSL_free(ssl);
          ::close(c);
        });
      }
    });
  }
  ~LoopbackTlsServer() {
    ::shutdown(fd_, SHUT_RDWR);
    ::close(fd_);
    accept_.join();
    for (auto& t : readers_) t.join();
    SSL_CTX_free(ctx_);
  }
  int port = 0;
  std::atomic<size_t> bytes{0};

 private:
  SSL_CTX* ctx_ = nullptr;
  int fd_ = -1;
  std::thread accept_;
  std::vector<std::thread> readers_;
};

}  // namespace

int main(int argc, char** argv) {
  const int entities = argc > 1 ? std::atoi(argv[1]) : 50;
  const int reports = argc > 2 ? std::atoi(argv[2]) : 20000;
  if (entities < 1 || reports < 1) {
    std::fprintf(stderr, "usage: bench_cop [entities >= 1] [reports >= 1]\n");
    return 2;
  }
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> pos(-500, 500);
  std::normal_distribution<double> noise(0, 3.0);
  std::vector<Eigen::Vector2d> truth(entities);
  for (auto& p : truth) p = {pos(rng), pos(rng)};

  // Each report: the entities one camera frame sees (a tenth of them).
  std::vector<std::vector<cop::Observation>> batches(reports);
  size_t observations = 0;
  for (int r = 0; r < reports; ++r) {
    for (int i = 0; i < entities; ++i) {
      if (rng() % 10) continue;
      cop::Observation o;
      o.stamp = r * 0.05;
      o.position = Eigen::Vector3d(truth[i].x() + noise(rng), truth[i].y() + noise(rng), 0);
      o.entity_class = "car";
      o.attributes = {{"color", i % 2 ? "white" : "red"}};
      o.confidence = 0.7;
      o.source = "bench";
      batches[r].push_back(o);
      observations++;
    }
  }
  cop::OperationalPicture picture;
  picture.setTargets({{"t", "car", {{"color", "white"}}}});
  auto t0 = Clock::now();
  for (int r = 0; r < reports; ++r) {
    picture.update(batches[r]);
    if (r % 20 == 0) picture.prune(r * 0.05);
  }
  const double fuse_s = std::chrono::duration<double>(Clock::now() - t0).count();

  const cop::EnuFrame frame({42.4851, -71.1873, 40.0});
  const cop::TakEventConfig config;
  std::vector<std::string> xml;
  t0 = Clock::now();
  const int rounds = 200;
  for (int k = 0; k < rounds; ++k) {
    for (const auto& [id, t] : picture.tracks()) {
      cop::TrackReport tr;
      tr.id = id;
      tr.entity_class = t.entity_class;
      tr.attributes = t.attributes();
      tr.position = Eigen::Vector3d(t.state.x(), t.state.y(), t.z);
      tr.ce = 3.0;
      tr.le = 1.0;
      xml.push_back(cop::toXml(cop::trackEvent(frame, tr, 1.8e9 + k, config)));
    }
  }
  const double build_s = std::chrono::duration<double>(Clock::now() - t0).count();
  // The same events as TAK Protocol Version 1 (stream frames).
  std::vector<cop::CotEvent> events;
  for (const auto& [id, t] : picture.tracks()) {
    cop::TrackReport tr;
    tr.id = id;
    tr.entity_class = t.entity_class;
    tr.attributes = t.attributes();
    tr.position = Eigen::Vector3d(t.state.x(), t.state.y(), t.z);
    events.push_back(cop::trackEvent(frame, tr, 1.8e9, config));
  }
  size_t proto_bytes = 0, proto_count = 0;
  t0 = Clock::now();
  for (int k = 0; k < rounds; ++k)
    for (const cop::CotEvent& e : events) {
      proto_bytes += cop::frameStream(cop::toTakProto(e)).size();
      proto_count++;
    }
  const double proto_s = std::chrono::duration<double>(Clock::now() - t0).count();

  // A bound loopback socket nobody reads: datagrams go to the kernel and are dropped there.
  const int rx = ::socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ::bind(rx, reinterpret_cast<sockaddr*>(&a), sizeof a);
  socklen_t len = sizeof a;
  ::getsockname(rx, reinterpret_cast<sockaddr*>(&a), &len);
  const int port = ntohs(a.sin_port);
  cop::TakSenderConfig sc;
  sc.queue_capacity = xml.size();
  double send_s = 0;
  std::uint64_t sent = 0;
  {
    cop::TakSender sender(cop::parseTakUrl("udp://127.0.0.1:" + std::to_string(port)), sc);
    t0 = Clock::now();
    for (const std::string& x : xml) sender.send(x);
    while (sender.stats().sent + sender.stats().send_errors < xml.size())
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    send_s = std::chrono::duration<double>(Clock::now() - t0).count();
    sent = sender.stats().sent;
  }
  ::close(rx);

  // Mutual TLS on loopback: certificates made here, a server that requires the client's.
  char tmpl[] = "/tmp/bench_cop_tls_XXXXXX";
  const std::string dir = mkdtemp(tmpl);
  const Cert ca = makeCert("bench CA", nullptr, true, dir + "/ca");
  const Cert server = makeCert("bench server", &ca, false, dir + "/server");
  const Cert client = makeCert("bench client", &ca, false, dir + "/client");
  double tls_send_s = 0;
  std::vector<double> handshakes;
  {
    LoopbackTlsServer tls_server(dir);
    cop::TakTlsConfig tc;
    tc.client_cert = dir + "/client.pem";
    tc.client_key = dir + "/client.key";
    tc.trust_store = dir + "/ca.pem";
    const cop::TakTlsContext context(tc);
    for (int i = 0; i < 20; ++i) {
      const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
      sockaddr_in sa{};
      sa.sin_family = AF_INET;
      sa.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
      sa.sin_port = htons(static_cast<uint16_t>(tls_server.port));
      const auto h0 = Clock::now();
      if (::connect(fd, reinterpret_cast<sockaddr*>(&sa), sizeof sa) == 0) {
        ::fcntl(fd, F_SETFL, O_NONBLOCK);
        cop::TakTlsConnection conn(context, fd, "127.0.0.1", 5.0);
        handshakes.push_back(std::chrono::duration<double>(Clock::now() - h0).count());
      }
      ::close(fd);
    }
    cop::TakSenderConfig tsc;
    tsc.queue_capacity = xml.size();
    tsc.tls = tc;
    size_t total = 0;
    for (const std::string& x : xml) total += x.size();
    const size_t before = tls_server.bytes;
    cop::TakSender sender(cop::parseTakUrl("ssl://127.0.0.1:" + std::to_string(tls_server.port)),
                          tsc);
    t0 = Clock::now();
    for (const std::string& x : xml) sender.send(x);
    while (tls_server.bytes - before < total && sender.stats().send_errors == 0 &&
           Clock::now() - t0 < std::chrono::seconds(60))
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    tls_send_s = std::chrono::duration<double>(Clock::now() - t0).count();
    if (tls_server.bytes - before != total)
      std::fprintf(stderr, "bench_cop: TLS server read %zu of %zu bytes (%s)\n",
                   tls_server.bytes - before, total, sender.stats().last_error.c_str());
  }
  for (const Cert* c : {&ca, &server, &client}) {
    EVP_PKEY_free(c->key);
    X509_free(c->cert);
  }
  std::system(("rm -rf " + dir).c_str());
  std::sort(handshakes.begin(), handshakes.end());

  size_t confirmed = 0;
  for (const auto& [id, t] : picture.tracks()) confirmed += t.confirmed;
  std::printf(
      "bench_cop: %d entities, %d reports, %zu observations -> %zu tracks (%zu confirmed)\n",
      entities, reports, observations, picture.tracks().size(), confirmed);
  std::printf("  fusion:    %.0f COP updates/s (reports), %.0f observations/s\n", reports / fuse_s,
              observations / fuse_s);
  std::printf("  CoT build: %.0f events/s (%zu events, mean %zu bytes)\n", xml.size() / build_s,
              xml.size(), xml.empty() ? 0 : xml.front().size());
  std::printf("  UDP send:  %.0f events/s to 127.0.0.1 (%llu of %zu sent)\n", sent / send_s,
              static_cast<unsigned long long>(sent), xml.size());
  std::printf("  TAK Protocol v1 build: %.0f events/s (%zu events, mean %zu bytes framed)\n",
              proto_count / proto_s, proto_count, proto_count ? proto_bytes / proto_count : 0);
  std::printf("  TLS send:  %.0f events/s to 127.0.0.1 (mutual TLS, CoT XML, read by the server)\n",
              xml.size() / tls_send_s);
  if (!handshakes.empty())
    std::printf("  TLS connect + handshake: median %.2f ms, max %.2f ms (%zu of 20)\n",
                handshakes[handshakes.size() / 2] * 1e3, handshakes.back() * 1e3,
                handshakes.size());
  return 0;
}
