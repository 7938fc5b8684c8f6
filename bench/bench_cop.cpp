// COP and CoT throughput: fuses reports of N entities (claims with 3 m noise) into the
// OperationalPicture, then builds the CoT XML events of every track (geodetic conversion
// included) and, separately, sends them as UDP datagrams to a loopback port nobody reads
// (127.0.0.1 only). Prints COP updates (reports) per second, observations per second, CoT
// events built per second and events sent per second.
//
// Usage: bench_cop [entities] [reports]

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

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
#include "hameritt/cop/tak_sender.h"

namespace cop = hameritt::cop;
using Clock = std::chrono::steady_clock;

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
  return 0;
}
