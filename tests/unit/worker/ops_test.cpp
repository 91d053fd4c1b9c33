// The worker's ops endpoint (worker/src/ops): /healthz, /readyz and /metrics served over real
// loopback sockets on an ephemeral port and read by a minimal HTTP client; the exposition
// format checked line by line; readiness on drain and on a queue that fails; listen addresses;
// job context in logs; stage timings kept out of the deterministic manifest.

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <atomic>
#include <cctype>
#include <cstdio>
#include <fstream>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <sstream>
#include <thread>

#include "csgtile/worker/log.h"
#include "csgtile/worker/queue.h"
#include "csgtile/worker/run.h"
#include "ops/metrics.h"
#include "ops/ops_server.h"
#include "ops/stage_clock.h"
#include "test_support.h"

namespace csgtile::worker::ops {
namespace {

namespace fs = std::filesystem;
using testing::HasSubstr;

struct HttpReply {
  int status = 0;
  std::map<std::string, std::string> headers;  // lower-case names
  std::string body;
  std::string raw;
};

/// Sends `request` to 127.0.0.1:port and reads the reply until the server closes.
HttpReply http_exchange(int port, const std::string& request) {
  HttpReply reply;
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  EXPECT_GE(fd, 0);
  timeval timeout{10, 0};  // a hung server fails the test instead of hanging it
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(static_cast<std::uint16_t>(port));
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0) {
    ::close(fd);
    return reply;  // status 0: refused
  }
  EXPECT_EQ(::send(fd, request.data(), request.size(), MSG_NOSIGNAL),
            static_cast<ssize_t>(request.size()));
  char buffer[4096];
  ssize_t n;
  while ((n = ::recv(fd, buffer, sizeof buffer, 0)) > 0)
    reply.raw.append(buffer, static_cast<std::size_t>(n));
  ::close(fd);
  const std::size_t head_end = reply.raw.find("\r\n\r\n");
  if (head_end == std::string::npos) return reply;
  std::istringstream head(reply.raw.substr(0, head_end));
  std::string line;
  std::getline(head, line);
  if (line.rfind("HTTP/1.1 ", 0) == 0) reply.status = std::stoi(line.substr(9, 3));
  while (std::getline(head, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const std::size_t colon = line.find(':');
    if (colon == std::string::npos) continue;
    std::string name = line.substr(0, colon);
    for (char& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    reply.headers[name] = line.substr(line.find_first_not_of(' ', colon + 1));
  }
  reply.body = reply.raw.substr(head_end + 4);
  return reply;
}

HttpReply http_get(int port, const std::string& path, const std::string& method = "GET") {
  return http_exchange(
      port, method + " " + path + " HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n");
}

/// Checks the Prometheus text format 0.0.4 line by line; returns samples as "name{labels}" →
/// value text. Every line is a HELP/TYPE comment or `name{labels} value`; each TYPE comes once
/// and before the samples of its family.
std::map<std::string, std::string> parse_exposition(const std::string& text) {
  static const std::regex comment(R"(^# (HELP|TYPE) ([a-zA-Z_:][a-zA-Z0-9_:]*) (.*)$)");
  static const std::regex sample_line(
      R"re(^([a-zA-Z_:][a-zA-Z0-9_:]*)(\{[a-zA-Z_][a-zA-Z0-9_]*="(?:[^"\\\n]|\\.)*"(?:,[a-zA-Z_][a-zA-Z0-9_]*="(?:[^"\\\n]|\\.)*")*\})? ((?:[-+]?[0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?)|\+Inf|-Inf|NaN)$)re");
  static const std::set<std::string> types = {"counter", "gauge", "histogram", "summary",
                                              "untyped"};
  std::map<std::string, std::string> samples;
  std::map<std::string, std::string> typed;  // family → type
  EXPECT_TRUE(!text.empty() && text.back() == '\n') << "the exposition ends with a newline";
  std::istringstream in(text);
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    std::smatch m;
    if (std::regex_match(line, m, comment)) {
      if (m[1] == "TYPE") {
        EXPECT_TRUE(types.contains(m[3].str())) << "line " << number << ": " << line;
        EXPECT_TRUE(typed.emplace(m[2].str(), m[3].str()).second) << "TYPE twice: " << line;
      }
      continue;
    }
    if (!std::regex_match(line, m, sample_line)) {
      ADD_FAILURE() << "line " << number << " is neither a comment nor a sample: \"" << line
                    << "\"";
      continue;
    }
    std::string family = m[1].str();
    for (const char* suffix : {"_bucket", "_sum", "_count"}) {
      const std::string s = suffix;
      if (!typed.contains(family) && family.size() > s.size() &&
          family.compare(family.size() - s.size(), s.size(), s) == 0) {
        family.resize(family.size() - s.size());
      }
    }
    EXPECT_TRUE(typed.contains(family)) << "sample before its TYPE: " << line;
    EXPECT_TRUE(samples.emplace(m[1].str() + m[2].str(), m[3].str()).second)
        << "duplicate sample: " << line;
  }
  return samples;
}

// ---- listen addresses ------------------------------------------------------------------------

TEST(OpsListenAddress, AcceptedForms) {
  ListenAddress a;
  ASSERT_TRUE(parse_listen_address("", "metrics.listen", a).ok());
  EXPECT_FALSE(a.enabled);
  ASSERT_TRUE(parse_listen_address("off", "metrics.listen", a).ok());
  EXPECT_FALSE(a.enabled);
  ASSERT_TRUE(parse_listen_address("127.0.0.1:9464", "metrics.listen", a).ok());
  EXPECT_TRUE(a.enabled);
  EXPECT_EQ(a.host, "127.0.0.1");
  EXPECT_EQ(a.port, 9464);
  ASSERT_TRUE(parse_listen_address(":9500", "x", a).ok());
  EXPECT_EQ(a.host, "127.0.0.1");  // loopback unless told otherwise
  EXPECT_EQ(a.port, 9500);
  ASSERT_TRUE(parse_listen_address("9501", "x", a).ok());
  EXPECT_EQ(a.host, "127.0.0.1");
  ASSERT_TRUE(parse_listen_address("localhost:0", "x", a).ok());
  EXPECT_EQ(a.host, "127.0.0.1");
  EXPECT_EQ(a.port, 0);
  ASSERT_TRUE(parse_listen_address("0.0.0.0:9464", "x", a).ok());
  EXPECT_EQ(a.host, "0.0.0.0");
  ASSERT_TRUE(parse_listen_address("[::1]:9464", "x", a).ok());
  EXPECT_EQ(a.host, "::1");
}

TEST(OpsListenAddress, BadAddressIsAClearConfigError) {
  for (const char* bad : {"db.example:9464", "127.0.0.1:70000", "127.0.0.1:", "::1:9464",
                          "[::1]9464", "1.2.3:80", "127.0.0.1:94a4", "[zz]:1"}) {
    ListenAddress a;
    const Failure f = parse_listen_address(bad, "--metrics-listen", a);
    EXPECT_EQ(f.code, ErrorCode::ConfigInvalid) << bad;
    EXPECT_THAT(f.message, HasSubstr("--metrics-listen")) << bad;
    EXPECT_THAT(f.message, HasSubstr(std::string("\"") + bad + "\"")) << f.message;
    EXPECT_FALSE(a.enabled) << bad;
  }
}

// ---- the endpoint over HTTP --------------------------------------------------------------------

class OpsServerTest : public ::testing::Test {
 protected:
  std::unique_ptr<OpsServer> start(std::chrono::milliseconds stall_after = std::chrono::hours(1)) {
    OpsOptions o;
    o.listen = {true, "127.0.0.1", 0};
    o.stall_after = stall_after;
    o.draining = [this] { return draining_.load(); };
    o.queue_counts = [this](QueueCounts& c) -> Failure {
      if (queue_down_) return {ErrorCode::Io, "cannot reach the queue (test)"};
      c = counts_;
      return {};
    };
    o.metrics = &metrics_;
    o.version = "9.8.7";
    Failure f;
    auto server = OpsServer::start(std::move(o), f);
    EXPECT_TRUE(f.ok()) << f.message;
    return server;
  }
  Metrics metrics_;
  std::atomic<bool> draining_{false};
  std::atomic<bool> queue_down_{false};
  QueueCounts counts_{2, 1, 7, 3, 1};
};

TEST_F(OpsServerTest, MetricsParseAndCarryTheRegistryAndQueue) {
  metrics_.job_claimed(1);
  metrics_.job_finished(JobOutcome::Done, 0.3);
  metrics_.job_claimed(2);  // a retry
  metrics_.job_finished(JobOutcome::Done, 42.0);
  metrics_.job_claimed(1);
  metrics_.job_finished(JobOutcome::Dead, 0.01);
  metrics_.add_bytes_fetched(1000);
  metrics_.add_bytes_fetched(24);
  metrics_.add_bytes_published(5);
  metrics_.add_points_processed(123456);
  metrics_.add_primitives_built(9);
  metrics_.add_stage_seconds("read", 0.25);
  metrics_.add_stage_seconds("read", 0.5);
  auto server = start();
  ASSERT_TRUE(server);
  ASSERT_GT(server->port(), 0);
  EXPECT_EQ(server->address(), "127.0.0.1:" + std::to_string(server->port()));
  const HttpReply r = http_get(server->port(), "/metrics");
  ASSERT_EQ(r.status, 200) << r.raw;
  EXPECT_EQ(r.headers.at("content-type"), "text/plain; version=0.0.4; charset=utf-8");
  EXPECT_EQ(std::stoul(r.headers.at("content-length")), r.body.size());
  const auto s = parse_exposition(r.body);
  EXPECT_EQ(s.at("csgtile_build_info{version=\"9.8.7\"}"), "1");
  EXPECT_EQ(s.at("csgtile_queue_up"), "1");
  EXPECT_EQ(s.at("csgtile_queue_jobs{state=\"queued\"}"), "2");
  EXPECT_EQ(s.at("csgtile_queue_jobs{state=\"running\"}"), "1");
  EXPECT_EQ(s.at("csgtile_queue_jobs{state=\"done\"}"), "7");
  EXPECT_EQ(s.at("csgtile_queue_jobs{state=\"retry\"}"), "3");
  EXPECT_EQ(s.at("csgtile_queue_jobs{state=\"dead\"}"), "1");
  EXPECT_EQ(s.at("csgtile_worker_jobs_total{outcome=\"done\"}"), "2");
  EXPECT_EQ(s.at("csgtile_worker_jobs_total{outcome=\"dead\"}"), "1");
  EXPECT_EQ(s.at("csgtile_worker_jobs_total{outcome=\"retry\"}"), "0");
  EXPECT_EQ(s.at("csgtile_worker_jobs_total{outcome=\"lease_lost\"}"), "0");
  EXPECT_EQ(s.at("csgtile_worker_job_retries_total"), "1");
  EXPECT_EQ(s.at("csgtile_fetched_bytes_total"), "1024");
  EXPECT_EQ(s.at("csgtile_published_bytes_total"), "5");
  EXPECT_EQ(s.at("csgtile_points_processed_total"), "123456");
  EXPECT_EQ(s.at("csgtile_primitives_built_total"), "9");
  EXPECT_EQ(s.at("csgtile_worker_stage_seconds_total{stage=\"read\"}"), "0.75");
  EXPECT_EQ(s.at("csgtile_worker_job_running"), "0");
  EXPECT_EQ(s.at("csgtile_worker_draining"), "0");
  // Histogram: cumulative buckets, +Inf equals the count, the sum of the three durations.
  EXPECT_EQ(s.at("csgtile_worker_job_duration_seconds_bucket{le=\"0.05\"}"), "1");
  EXPECT_EQ(s.at("csgtile_worker_job_duration_seconds_bucket{le=\"0.5\"}"), "2");
  EXPECT_EQ(s.at("csgtile_worker_job_duration_seconds_bucket{le=\"30\"}"), "2");
  EXPECT_EQ(s.at("csgtile_worker_job_duration_seconds_bucket{le=\"60\"}"), "3");
  EXPECT_EQ(s.at("csgtile_worker_job_duration_seconds_bucket{le=\"+Inf\"}"), "3");
  EXPECT_EQ(s.at("csgtile_worker_job_duration_seconds_count"), "3");
  EXPECT_DOUBLE_EQ(std::stod(s.at("csgtile_worker_job_duration_seconds_sum")), 42.31);
  double previous = 0;
  for (const double le : Metrics::duration_buckets()) {
    std::string key = "csgtile_worker_job_duration_seconds_bucket{le=\"";
    append_sample_value(key, le);
    const double count = std::stod(s.at(key + "\"}"));
    EXPECT_GE(count, previous) << key;
    previous = count;
  }
  // HEAD: the same head, no body.
  const HttpReply head = http_get(server->port(), "/metrics", "HEAD");
  EXPECT_EQ(head.status, 200);
  EXPECT_TRUE(head.body.empty());
}

TEST_F(OpsServerTest, LabelValuesAreEscaped) {
  metrics_.add_stage_seconds("odd \"stage\"\\\nname", 1);
  auto server = start();
  ASSERT_TRUE(server);
  const auto s = parse_exposition(http_get(server->port(), "/metrics").body);
  EXPECT_EQ(s.at("csgtile_worker_stage_seconds_total{stage=\"odd \\\"stage\\\"\\\\\\nname\"}"),
            "1");
}

TEST_F(OpsServerTest, ReadinessFlipsOnDrainAndOnAQueueThatFails) {
  auto server = start();
  ASSERT_TRUE(server);
  HttpReply r = http_get(server->port(), "/readyz");
  EXPECT_EQ(r.status, 200) << r.raw;
  EXPECT_EQ(nlohmann::json::parse(r.body)["status"], "ready");
  draining_ = true;  // SIGTERM: stop claiming
  r = http_get(server->port(), "/readyz");
  EXPECT_EQ(r.status, 503);
  EXPECT_EQ(nlohmann::json::parse(r.body)["draining"], true);
  EXPECT_EQ(
      parse_exposition(http_get(server->port(), "/metrics").body).at("csgtile_worker_draining"),
      "1");
  // Draining is not dead: liveness still holds.
  EXPECT_EQ(http_get(server->port(), "/healthz").status, 200);
  draining_ = false;
  queue_down_ = true;
  r = http_get(server->port(), "/readyz");
  EXPECT_EQ(r.status, 503);
  EXPECT_THAT(nlohmann::json::parse(r.body)["queue"].get<std::string>(),
              HasSubstr("cannot reach the queue"));
  const auto s = parse_exposition(http_get(server->port(), "/metrics").body);
  EXPECT_EQ(s.at("csgtile_queue_up"), "0");
  EXPECT_FALSE(s.contains("csgtile_queue_jobs{state=\"queued\"}"));
}

TEST_F(OpsServerTest, LivenessFailsWithoutProgressUnlessALongStepRuns) {
  auto stalled = start(std::chrono::milliseconds(0));  // any time without progress is too long
  ASSERT_TRUE(stalled);
  HttpReply r = http_get(stalled->port(), "/healthz");
  EXPECT_EQ(r.status, 503) << r.raw;
  EXPECT_EQ(nlohmann::json::parse(r.body)["status"], "stalled");
  {
    const LongStepScope publishing(metrics_, "publish");
    r = http_get(stalled->port(), "/healthz");
    EXPECT_EQ(r.status, 200) << r.raw;
    EXPECT_EQ(nlohmann::json::parse(r.body)["long_step"], "publish");
  }
  EXPECT_EQ(http_get(stalled->port(), "/healthz").status, 503);
  auto patient = start(std::chrono::hours(1));
  ASSERT_TRUE(patient);
  r = http_get(patient->port(), "/healthz");
  EXPECT_EQ(r.status, 200) << r.raw;
  EXPECT_EQ(nlohmann::json::parse(r.body)["status"], "ok");
}

TEST_F(OpsServerTest, UnknownPathsMethodsAndMalformedRequests) {
  auto server = start();
  ASSERT_TRUE(server);
  EXPECT_EQ(http_get(server->port(), "/nope").status, 404);
  EXPECT_EQ(http_get(server->port(), "/metrics?x=1").status, 200);  // queries are ignored
  const HttpReply post = http_get(server->port(), "/metrics", "POST");
  EXPECT_EQ(post.status, 405);
  EXPECT_EQ(post.headers.at("allow"), "GET, HEAD");
  EXPECT_EQ(http_exchange(server->port(), "garbage\r\n\r\n").status, 400);
  EXPECT_EQ(http_exchange(server->port(), "GET /metrics SMTP/1.0\r\n\r\n").status, 400);
  EXPECT_EQ(
      http_exchange(server->port(), "GET /x HTTP/1.1\r\nX: " + std::string(10000, 'a') + "\r\n\r\n")
          .status,
      431);
  // A client that connects and sends nothing holds one thread until the deadline; the other
  // thread keeps answering.
  const int idle = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(static_cast<std::uint16_t>(server->port()));
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(::connect(idle, reinterpret_cast<sockaddr*>(&address), sizeof address), 0);
  EXPECT_EQ(http_get(server->port(), "/healthz").status, 200);
  ::close(idle);
}

TEST_F(OpsServerTest, PortInUseIsAClearErrorAndStopReleasesIt) {
  auto first = start();
  ASSERT_TRUE(first);
  OpsOptions o;
  o.listen = {true, "127.0.0.1", first->port()};
  o.metrics = &metrics_;
  Failure f;
  auto second = OpsServer::start(o, f);
  EXPECT_FALSE(second);
  EXPECT_EQ(f.code, ErrorCode::Io);
  EXPECT_THAT(f.message, HasSubstr("127.0.0.1:" + std::to_string(first->port())));
  EXPECT_THAT(f.message, HasSubstr("Address already in use"));
  EXPECT_THAT(f.message, HasSubstr("--metrics-listen"));
  first->stop();
  first->stop();  // idempotent
  EXPECT_EQ(http_get(o.listen.port, "/healthz").status, 0) << "refused once stopped";
  second = OpsServer::start(o, f);  // the port is free again
  ASSERT_TRUE(second) << f.message;
  EXPECT_EQ(http_get(second->port(), "/healthz").status, 200);
}

TEST_F(OpsServerTest, DisabledAddressIsNotStarted) {
  OpsOptions o;  // listen not enabled
  Failure f;
  EXPECT_FALSE(OpsServer::start(o, f));
  EXPECT_EQ(f.code, ErrorCode::ConfigInvalid);
}

TEST(OpsServer, JobsByStateFromARealSqliteQueue) {
  const fs::path dir = fs::temp_directory_path() / ("csgtile-ops-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  Failure f;
  auto queue = open_sqlite_queue(dir / "queue.sqlite", QueuePolicy{}, f);
  ASSERT_TRUE(queue) << f.message;
  for (const char* key : {"a", "b", "c"}) queue->enqueue(key, "build", "{}", f);
  ASSERT_TRUE(queue->claim("w", f).has_value());
  std::mutex mutex;
  OpsOptions o;
  o.listen = {true, "127.0.0.1", 0};
  o.queue_counts = [&](QueueCounts& c) {
    const std::lock_guard lock(mutex);
    Failure failure;
    c = queue->counts(failure);
    return failure;
  };
  Metrics registry;
  o.metrics = &registry;
  auto server = OpsServer::start(o, f);
  ASSERT_TRUE(server) << f.message;
  const auto s = parse_exposition(http_get(server->port(), "/metrics").body);
  EXPECT_EQ(s.at("csgtile_queue_jobs{state=\"queued\"}"), "2");
  EXPECT_EQ(s.at("csgtile_queue_jobs{state=\"running\"}"), "1");
  EXPECT_EQ(s.at("csgtile_queue_jobs{state=\"done\"}"), "0");
  EXPECT_EQ(http_get(server->port(), "/readyz").status, 200);
  server.reset();
  queue.reset();
  fs::remove_all(dir);
}

// ---- logs and stage timings ---------------------------------------------------------------------

std::vector<nlohmann::json> json_lines(std::FILE* file) {
  std::fflush(file);
  std::rewind(file);
  std::vector<nlohmann::json> lines;
  char buffer[4096];
  while (std::fgets(buffer, sizeof buffer, file)) lines.push_back(nlohmann::json::parse(buffer));
  return lines;
}

TEST(OpsLogs, JobContextRidesOnLinesWhileAJobRuns) {
  std::FILE* file = std::tmpfile();
  ASSERT_NE(file, nullptr);
  Logger log(config::LogLevel::Info, config::LogFormat::Json, file);
  log.info("worker", "before");
  {
    const LogJobScope scope("city", "build:city:a.json", 2);
    log.info("job", "inside", {{"seconds", "1.5"}});
    std::thread([&log] { log.info("other", "another thread"); }).join();
  }
  log.info("worker", "after");
  const auto lines = json_lines(file);
  ASSERT_EQ(lines.size(), 4u);
  EXPECT_FALSE(lines[0].contains("job"));
  EXPECT_FALSE(lines[0].contains("run"));
  EXPECT_EQ(lines[1]["run"], "city");
  EXPECT_EQ(lines[1]["job"], "build:city:a.json");
  EXPECT_EQ(lines[1]["attempt"], 2);
  EXPECT_EQ(lines[1]["seconds"], "1.5");
  EXPECT_FALSE(lines[2].contains("job")) << "the context is per thread";
  EXPECT_FALSE(lines[3].contains("job"));
  std::fclose(file);
}

TEST(OpsTimings, StageClockAccumulatesInOrderOfFirstEntry) {
  StageTimings t;
  {
    StageClock clock(&t);
    clock.enter("read");
    clock.enter("build");
    clock.enter("check");
    clock.enter("build");
    clock.enter("publish");
  }
  ASSERT_EQ(t.seconds.size(), 4u);
  EXPECT_EQ(t.seconds[0].first, "read");
  EXPECT_EQ(t.seconds[1].first, "build");
  EXPECT_EQ(t.seconds[2].first, "check");
  EXPECT_EQ(t.seconds[3].first, "publish");
  for (const auto& [stage, seconds] : t.seconds) EXPECT_GE(seconds, 0) << stage;
}

TEST(OpsTimings, RunWritesTimingsBesideAManifestWithoutThem) {
  const fs::path dir =
      fs::temp_directory_path() / ("csgtile-ops-run-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  config::Config c;
  c.run.name = "timed";
  c.run.output = (dir / "out").string();
  c.run.inputs = {(test::source_dir() / "config/examples/scenes/pavilion.json").string()};
  c.metrics.listen = "127.0.0.1:1";  // per process: must not change the manifest's config hash
  Logger log(config::LogLevel::Error, config::LogFormat::Json, stderr);
  const auto published_before =
      parse_exposition(metrics().exposition()).at("csgtile_published_bytes_total");
  RunSummary summary;
  ASSERT_TRUE(run_embedded(c, log, summary).ok());
  const auto manifest = nlohmann::json::parse(test::read_file(summary.manifest));
  ASSERT_EQ(manifest["jobs"].size(), 1u);
  EXPECT_FALSE(manifest["jobs"][0]["result"].contains("timings"))
      << "timings stay out of manifest.json";
  EXPECT_EQ(manifest["timings"], "timings.json");
  // ordered_json: the file lists stages in the order they first ran.
  const auto timings =
      nlohmann::ordered_json::parse(test::read_file(summary.run_dir / "timings.json"));
  ASSERT_EQ(timings["jobs"].size(), 1u);
  const auto& job = timings["jobs"][0];
  EXPECT_EQ(job["key"], manifest["jobs"][0]["key"]);
  EXPECT_EQ(job["attempt"], 1);
  std::vector<std::string> stages;
  for (const auto& [stage, seconds] : job["stages"].items()) {
    stages.push_back(stage);
    EXPECT_GE(seconds.get<double>(), 0) << stage;
  }
  // The scene stages in the order they ran (a "fetch" stage may come first).
  std::vector<std::string> scene_stages;
  for (const std::string& stage : stages) {
    if (stage != "fetch") scene_stages.push_back(stage);
  }
  EXPECT_THAT(scene_stages, testing::ElementsAre("read", "build", "check", "publish"));
  EXPECT_GE(job["seconds"].get<double>(), 0);
  // Bytes written by the run count as published.
  const auto after = parse_exposition(metrics().exposition());
  EXPECT_GT(std::stod(after.at("csgtile_published_bytes_total")), std::stod(published_before));
  // The same run republished from the same queue by a process without the endpoint: the
  // manifest keeps its bytes (the listen address is not hashed).
  const std::string before = test::read_file(summary.manifest);
  config::Config without = c;
  without.metrics = {};
  RunSummary again;
  ASSERT_TRUE(run_embedded(without, log, again).ok());
  EXPECT_EQ(test::read_file(again.manifest), before);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace csgtile::worker::ops
