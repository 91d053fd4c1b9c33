// Why plain POSIX sockets rather than cpp-httplib: Debian's libcpp-httplib-dev 0.11 is not
// header-only (the implementation lives in libcpp-httplib.so, built with OpenSSL, zlib and
// brotli, and the header's class layouts depend on matching -D flags), which would add a
// runtime package to the image and an ABI trap for three GET routes with small bodies. Here
// each bind error keeps its errno for the start-up message, signals stay with the main
// thread, and stop() is a pipe write and a join.

#include "ops/ops_server.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <pthread.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstring>
#include <exception>
#include <nlohmann/json.hpp>
#include <system_error>
#include <thread>
#include <utility>
#include <vector>

namespace csgtile::worker::ops {

namespace {

constexpr std::size_t kMaxRequestBytes = 8192;

Failure bad_listen(std::string_view what, std::string_view text, const std::string& reason) {
  return {ErrorCode::ConfigInvalid,
          std::string(what) + ": " + reason + " (got \"" + std::string(text) +
              "\"; expected HOST:PORT such as 127.0.0.1:" + std::to_string(kDefaultPort) +
              ", [::1]:PORT, :PORT, or \"off\")"};
}

}  // namespace

Failure parse_listen_address(std::string_view text, std::string_view what, ListenAddress& out) {
  out = ListenAddress{};
  if (text.empty() || text == "off") return {};
  std::string host;
  std::string_view port_text;
  if (text.front() == '[') {
    const std::size_t close = text.find("]:");
    if (close == std::string_view::npos)
      return bad_listen(what, text, "an IPv6 address needs \"]:PORT\"");
    host = std::string(text.substr(1, close - 1));
    port_text = text.substr(close + 2);
    in6_addr a6{};
    if (inet_pton(AF_INET6, host.c_str(), &a6) != 1) {
      return bad_listen(what, text, "\"" + host + "\" is not an IPv6 address");
    }
  } else {
    const std::size_t colon = text.rfind(':');
    if (colon == std::string_view::npos) {
      port_text = text;  // a bare port: loopback
    } else {
      host = std::string(text.substr(0, colon));
      port_text = text.substr(colon + 1);
      if (host.find(':') != std::string::npos) {
        return bad_listen(what, text, "write an IPv6 address in brackets");
      }
    }
    if (host.empty() || host == "localhost") host = "127.0.0.1";
    in_addr a4{};
    if (inet_pton(AF_INET, host.c_str(), &a4) != 1) {
      return bad_listen(what, text,
                        "\"" + host +
                            "\" is not an IPv4 address (host names other than localhost "
                            "are not resolved)");
    }
  }
  if (port_text.empty() || port_text.size() > 5 ||
      port_text.find_first_not_of("0123456789") != std::string_view::npos) {
    return bad_listen(what, text, "the port must be a number 0..65535");
  }
  const int port = std::stoi(std::string(port_text));
  if (port > 65535) return bad_listen(what, text, "the port must be a number 0..65535");
  out.enabled = true;
  out.host = host;
  out.port = port;
  return {};
}

struct OpsServer::State {
  OpsOptions options;
  Metrics* metrics = nullptr;
  int listen_fd = -1;
  int wake_read = -1;
  int wake_write = -1;
  int port = 0;
  bool ipv6 = false;
  std::vector<std::thread> threads;
  std::atomic<bool> stopped{false};

  ~State() {
    for (const int fd : {listen_fd, wake_read, wake_write}) {
      if (fd >= 0) ::close(fd);
    }
  }
};

namespace {

const char* reason_phrase(int status) {
  switch (status) {
    case 200:
      return "OK";
    case 400:
      return "Bad Request";
    case 404:
      return "Not Found";
    case 405:
      return "Method Not Allowed";
    case 431:
      return "Request Header Fields Too Large";
    case 500:
      return "Internal Server Error";
    case 503:
      return "Service Unavailable";
  }
  return "Unknown";
}

int remaining_ms(std::chrono::steady_clock::time_point deadline) {
  const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
      deadline - std::chrono::steady_clock::now());
  return left.count() > 0 ? static_cast<int>(left.count()) : 0;
}

/// Sends all of `data` before `deadline`; false when the peer went away or was too slow.
bool send_all(int fd, std::string_view data, std::chrono::steady_clock::time_point deadline) {
  std::size_t sent = 0;
  while (sent < data.size()) {
    const ssize_t n = ::send(fd, data.data() + sent, data.size() - sent, MSG_NOSIGNAL);
    if (n > 0) {
      sent += static_cast<std::size_t>(n);
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
      pollfd p{fd, POLLOUT, 0};
      const int wait = remaining_ms(deadline);
      if (wait == 0 || ::poll(&p, 1, wait) <= 0) return false;
      continue;
    }
    return false;
  }
  return true;
}

std::string json_body(const nlohmann::ordered_json& j) { return j.dump() + "\n"; }

}  // namespace

OpsServer::OpsServer(std::unique_ptr<State> state) : state_(std::move(state)) {}

OpsServer::~OpsServer() { stop(); }

int OpsServer::port() const { return state_->port; }

std::string OpsServer::address() const {
  const std::string& host = state_->options.listen.host;
  return (state_->ipv6 ? "[" + host + "]" : host) + ":" + std::to_string(state_->port);
}

OpsServer::Response OpsServer::handle(std::string_view method, std::string_view target) const {
  const OpsOptions& o = state_->options;
  const std::string_view path = target.substr(0, target.find('?'));
  if (method != "GET" && method != "HEAD") {
    return {405, "text/plain; charset=utf-8", "only GET and HEAD are served\n"};
  }
  if (path == "/healthz") {
    const Metrics::Liveness l = state_->metrics->liveness();
    const double stall_after = std::chrono::duration<double>(o.stall_after).count();
    const bool live = !l.long_step.empty() || l.seconds_since_progress <= stall_after;
    nlohmann::ordered_json j{{"status", live ? "ok" : "stalled"},
                             {"seconds_since_progress", l.seconds_since_progress},
                             {"stall_after_seconds", stall_after}};
    if (!l.long_step.empty()) j["long_step"] = l.long_step;
    return {live ? 200 : 503, "application/json", json_body(j)};
  }
  if (path == "/readyz") {
    const bool draining = o.draining && o.draining();
    std::string queue = "none";
    bool queue_ok = true;
    if (o.queue_counts) {
      QueueCounts counts;
      const Failure f = o.queue_counts(counts);
      queue_ok = f.ok();
      queue = queue_ok ? "ok" : std::string(error_info(f.code).name) + ": " + f.message;
    }
    const bool ready = !draining && queue_ok;
    nlohmann::ordered_json j{
        {"status", ready ? "ready" : "not ready"}, {"draining", draining}, {"queue", queue}};
    return {ready ? 200 : 503, "application/json",
            j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) + "\n"};
  }
  if (path == "/metrics") {
    std::string out;
    out += "# HELP csgtile_build_info Version of this csgtile binary (the value is always 1).\n";
    out += "# TYPE csgtile_build_info gauge\n";
    out += "csgtile_build_info{version=\"" + escape_label_value(o.version) + "\"} 1\n";
    const bool draining = o.draining && o.draining();
    out += "# HELP csgtile_worker_draining 1 once the worker stopped claiming jobs (SIGTERM).\n";
    out += "# TYPE csgtile_worker_draining gauge\n";
    out += std::string("csgtile_worker_draining ") + (draining ? "1" : "0") + "\n";
    if (o.queue_counts) {
      QueueCounts c;
      const Failure f = o.queue_counts(c);
      out += "# HELP csgtile_queue_up 1 when the last read of the queue succeeded.\n";
      out += "# TYPE csgtile_queue_up gauge\n";
      out += std::string("csgtile_queue_up ") + (f.ok() ? "1" : "0") + "\n";
      if (f.ok()) {
        out += "# HELP csgtile_queue_jobs Jobs in the queue, by state (all workers).\n";
        out += "# TYPE csgtile_queue_jobs gauge\n";
        const std::pair<JobState, std::int64_t> states[] = {{JobState::Queued, c.queued},
                                                            {JobState::Running, c.running},
                                                            {JobState::Done, c.done},
                                                            {JobState::Retry, c.retry},
                                                            {JobState::Dead, c.dead}};
        for (const auto& [state, n] : states) {
          out += std::string("csgtile_queue_jobs{state=\"") + job_state_name(state) + "\"} " +
                 std::to_string(n) + "\n";
        }
      }
    }
    out += state_->metrics->exposition();
    return {200, "text/plain; version=0.0.4; charset=utf-8", out};
  }
  if (path == "/") {
    return {200, "text/plain; charset=utf-8", "csgtile worker: /healthz /readyz /metrics\n"};
  }
  return {404, "text/plain; charset=utf-8", "not found; try /healthz, /readyz or /metrics\n"};
}

namespace {

/// Reads one request head from `fd` before `deadline`, answers it and returns.
void serve_connection(const OpsServer& server, int fd, std::chrono::milliseconds budget) {
  const auto deadline = std::chrono::steady_clock::now() + budget;
  std::string request;
  char buffer[1024];
  bool complete = false;
  while (!complete && request.size() <= kMaxRequestBytes) {
    const ssize_t n = ::recv(fd, buffer, sizeof buffer, 0);
    if (n > 0) {
      request.append(buffer, static_cast<std::size_t>(n));
      complete = request.find("\r\n\r\n") != std::string::npos;
      continue;
    }
    if (n == 0) return;  // the peer closed before a whole request
    if (errno == EINTR) continue;
    if (errno != EAGAIN && errno != EWOULDBLOCK) return;
    pollfd p{fd, POLLIN, 0};
    const int wait = remaining_ms(deadline);
    if (wait == 0 || ::poll(&p, 1, wait) <= 0) return;  // too slow: drop without an answer
  }
  OpsServer::Response response;
  std::string_view method;
  if (!complete) {
    response = {431, "text/plain; charset=utf-8", "request head too large\n"};
  } else {
    // Request line: METHOD SP TARGET SP HTTP/1.x
    const std::string_view line = std::string_view{request}.substr(0, request.find("\r\n"));
    const std::size_t a = line.find(' ');
    const std::size_t b = a == std::string_view::npos ? a : line.find(' ', a + 1);
    if (b == std::string_view::npos || line.substr(b + 1).rfind("HTTP/1.", 0) != 0 ||
        line.substr(a + 1, b - a - 1).empty()) {
      response = {400, "text/plain; charset=utf-8", "malformed request line\n"};
    } else {
      method = line.substr(0, a);
      try {
        response = server.handle(method, line.substr(a + 1, b - a - 1));
      } catch (const std::exception& e) {
        response = {500, "text/plain; charset=utf-8",
                    std::string("internal error: ") + e.what() + "\n"};
      }
    }
  }
  std::string head = "HTTP/1.1 " + std::to_string(response.status) + " " +
                     reason_phrase(response.status) + "\r\nContent-Type: " + response.content_type +
                     "\r\nContent-Length: " + std::to_string(response.body.size()) +
                     "\r\nCache-Control: no-store\r\nConnection: close\r\n";
  if (response.status == 405) head += "Allow: GET, HEAD\r\n";
  head += "\r\n";
  if (method != "HEAD") head += response.body;
  if (!send_all(fd, head, deadline)) return;
  ::shutdown(fd, SHUT_WR);
  // Read what the client sent beyond the head (already here on loopback): closing a socket
  // with unread input sends a reset, which may discard the answer at the client.
  for (std::size_t drained = 0; drained < 65536;) {
    const ssize_t n = ::recv(fd, buffer, sizeof buffer, 0);
    if (n <= 0) break;
    drained += static_cast<std::size_t>(n);
  }
}

}  // namespace

std::unique_ptr<OpsServer> OpsServer::start(OpsOptions options, Failure& failure) {
  failure = {};
  if (!options.listen.enabled) {
    failure = {ErrorCode::ConfigInvalid,
               "the metrics endpoint is not enabled (listen address \"off\")"};
    return nullptr;
  }
  auto state = std::make_unique<State>();
  state->metrics = options.metrics ? options.metrics : &metrics();
  state->options = std::move(options);
  const ListenAddress& listen = state->options.listen;
  const std::string where =
      (listen.host.find(':') != std::string::npos ? "[" + listen.host + "]" : listen.host) + ":" +
      std::to_string(listen.port);
  const auto io_error = [&](const std::string& what, int err) {
    std::string message = "metrics endpoint: cannot " + what + " " + where + ": " +
                          std::generic_category().message(err);
    if (err == EADDRINUSE) {
      message +=
          " (another process holds the port: choose another with --metrics-listen or "
          "metrics.listen, or \"off\")";
    }
    return Failure{ErrorCode::Io, message};
  };

  sockaddr_storage address{};
  socklen_t length = 0;
  in6_addr a6{};
  in_addr a4{};
  if (inet_pton(AF_INET6, listen.host.c_str(), &a6) == 1) {
    state->ipv6 = true;
    auto* sa = reinterpret_cast<sockaddr_in6*>(&address);
    sa->sin6_family = AF_INET6;
    sa->sin6_addr = a6;
    sa->sin6_port = htons(static_cast<std::uint16_t>(listen.port));
    length = sizeof(sockaddr_in6);
  } else if (inet_pton(AF_INET, listen.host.c_str(), &a4) == 1) {
    auto* sa = reinterpret_cast<sockaddr_in*>(&address);
    sa->sin_family = AF_INET;
    sa->sin_addr = a4;
    sa->sin_port = htons(static_cast<std::uint16_t>(listen.port));
    length = sizeof(sockaddr_in);
  } else {
    failure = {ErrorCode::ConfigInvalid,
               "metrics endpoint: \"" + listen.host + "\" is not an IP address"};
    return nullptr;
  }
  state->listen_fd = ::socket(address.ss_family, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
  if (state->listen_fd < 0) {
    failure = io_error("open a socket for", errno);
    return nullptr;
  }
  // SO_REUSEADDR only lets a restarted worker bind over its old TIME_WAIT connections; on
  // Linux a port with a live listener still fails with EADDRINUSE.
  const int one = 1;
  ::setsockopt(state->listen_fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  if (state->ipv6) ::setsockopt(state->listen_fd, IPPROTO_IPV6, IPV6_V6ONLY, &one, sizeof one);
  if (::bind(state->listen_fd, reinterpret_cast<const sockaddr*>(&address), length) != 0) {
    failure = io_error("listen on", errno);
    return nullptr;
  }
  if (::listen(state->listen_fd, 16) != 0) {
    failure = io_error("listen on", errno);
    return nullptr;
  }
  sockaddr_storage bound{};
  socklen_t bound_length = sizeof bound;
  ::getsockname(state->listen_fd, reinterpret_cast<sockaddr*>(&bound), &bound_length);
  state->port =
      ntohs(bound.ss_family == AF_INET6 ? reinterpret_cast<sockaddr_in6*>(&bound)->sin6_port
                                        : reinterpret_cast<sockaddr_in*>(&bound)->sin_port);
  int wake[2];
  if (::pipe2(wake, O_CLOEXEC | O_NONBLOCK) != 0) {
    failure = io_error("create a wake-up pipe for", errno);
    return nullptr;
  }
  state->wake_read = wake[0];
  state->wake_write = wake[1];

  std::unique_ptr<OpsServer> server(new OpsServer(std::move(state)));
  State& s = *server->state_;
  // The server's threads block every signal: SIGTERM and SIGINT reach the main thread, whose
  // claim-loop sleep they cut short (stop_signal.h).
  sigset_t all;
  sigset_t previous;
  sigfillset(&all);
  pthread_sigmask(SIG_BLOCK, &all, &previous);
  const int threads = std::max(1, s.options.threads);
  const OpsServer* self = server.get();
  for (int i = 0; i < threads; ++i) {
    s.threads.emplace_back([self, &s] {
      while (true) {
        pollfd fds[2] = {{s.listen_fd, POLLIN, 0}, {s.wake_read, POLLIN, 0}};
        if (::poll(fds, 2, -1) < 0) {
          if (errno == EINTR) continue;
          return;
        }
        if (fds[1].revents != 0) return;  // stop(): the pipe stays readable for every thread
        const int fd = ::accept4(s.listen_fd, nullptr, nullptr, SOCK_CLOEXEC | SOCK_NONBLOCK);
        if (fd < 0) {
          // Out of descriptors or memory: back off instead of spinning on a readable socket.
          if (errno == EMFILE || errno == ENFILE || errno == ENOBUFS || errno == ENOMEM) {
            std::this_thread::sleep_for(std::chrono::milliseconds(100));
          }
          continue;  // else another thread took it, or the client left
        }
        serve_connection(*self, fd, s.options.request_deadline);
        ::close(fd);
      }
    });
  }
  pthread_sigmask(SIG_SETMASK, &previous, nullptr);
  return server;
}

void OpsServer::stop() {
  if (!state_ || state_->stopped.exchange(true)) return;
  const char byte = 1;
  while (::write(state_->wake_write, &byte, 1) < 0 && errno == EINTR) {
  }
  for (std::thread& t : state_->threads) {
    if (t.joinable()) t.join();
  }
  state_->threads.clear();
  ::close(state_->listen_fd);
  state_->listen_fd = -1;
}

}  // namespace csgtile::worker::ops
