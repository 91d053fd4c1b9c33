#pragma once
// The worker's operations endpoint: a small HTTP/1.1 server (plain POSIX sockets) with
//   GET /healthz  liveness: 200 while the work loop progressed within `stall_after`, else 503
//   GET /readyz   readiness: 200 when the queue answers and the worker is not draining, else 503
//   GET /metrics  Prometheus text exposition format 0.0.4 (metrics.h, plus the queue's jobs
//                 by state and build info)
// Loopback by default (metrics.listen / --metrics-listen). Every request is answered with
// `Connection: close`; a request must arrive whole within a short deadline, so a slow or idle
// client holds one of the server's few threads for at most that long.

#include <chrono>
#include <functional>
#include <memory>
#include <string>
#include <string_view>

#include "csgtile/worker/errors.h"
#include "csgtile/worker/queue.h"
#include "ops/metrics.h"

namespace csgtile::worker::ops {

/// The documented default port of the endpoint (Prometheus exporters' range; deploy's probes).
inline constexpr int kDefaultPort = 9464;

struct ListenAddress {
  bool enabled = false;
  std::string host;  ///< numeric IPv4 or IPv6 address (without brackets)
  int port = 0;      ///< 0: the system picks a free port (see OpsServer::port())
};

/// Parses a listen address: "" or "off" (disabled), "HOST:PORT" with HOST an IPv4 address,
/// "[IPv6]:PORT" or "localhost", or ":PORT" / "PORT" for 127.0.0.1. PORT is 0..65535 (0: any
/// free port). Error ConfigInvalid naming `what` (the key or flag) and the text.
Failure parse_listen_address(std::string_view text, std::string_view what, ListenAddress& out);

/// How the endpoint learns the worker's state; every callback may be called from the
/// server's threads at any time, concurrently, so each must be thread-safe.
struct OpsOptions {
  ListenAddress listen;
  /// Liveness fails when the work loop made no progress for this long (outside a long step).
  std::chrono::milliseconds stall_after{std::chrono::minutes(3)};
  /// True once the worker drains (SIGTERM): readiness fails.
  std::function<bool()> draining;
  /// Counts the queue's jobs per state; a failure makes readiness fail and leaves the
  /// per-state gauge out of /metrics. Empty: no queue (readiness then depends on draining only).
  std::function<Failure(QueueCounts&)> queue_counts;
  Metrics* metrics = nullptr;  ///< nullptr: the process registry, metrics()
  std::string version;         ///< build info label
  int threads = 2;             ///< connections served at once
  std::chrono::milliseconds request_deadline{std::chrono::seconds(2)};
};

class OpsServer {
 public:
  /// Binds and starts serving. Errors: ConfigInvalid (listen not enabled), Io (cannot bind,
  /// e.g. the port is in use: the message names the address and the system's reason).
  static std::unique_ptr<OpsServer> start(OpsOptions options, Failure& failure);
  ~OpsServer();  ///< stops
  OpsServer(const OpsServer&) = delete;
  OpsServer& operator=(const OpsServer&) = delete;

  /// Stops accepting, lets requests in progress finish (each within its deadline), joins the
  /// threads and closes the socket. Idempotent.
  void stop();
  /// The bound port (the system's choice when the address asked for port 0).
  int port() const;
  /// "HOST:PORT" as bound ("[::1]:PORT" for IPv6), for logs.
  std::string address() const;

  /// The bodies the endpoint serves, for callers that want them without HTTP.
  struct Response {
    int status = 200;
    std::string content_type;
    std::string body;
  };
  Response handle(std::string_view method, std::string_view target) const;

 private:
  struct State;
  explicit OpsServer(std::unique_ptr<State> state);
  std::unique_ptr<State> state_;
};

}  // namespace csgtile::worker::ops
