// Fetch with libcurl against real loopback servers: a fault-injecting HTTP server
// (tests/support/fault_http_server.py) and @20minutes/s3rver, which checks SigV4 signatures.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "background_process.h"
#include "csgtile/worker/publish.h"
#include "fetch/fetch.h"
#include "fetch/sigv4.h"
#include "s3_test_server.h"
#include "test_commands.h"
#include "test_support.h"

namespace fs = std::filesystem;
using namespace csgtile::worker;
using csgtile::test::BackgroundProcess;
using csgtile::test::quoted;
using csgtile::test::ScopedEnv;

namespace {

std::string file_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_text(const fs::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

// Files under `dir` (recursively), hidden ones included: a failed fetch leaves none.
std::size_t regular_files(const fs::path& dir) {
  std::size_t n = 0;
  if (!fs::exists(dir)) return 0;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) n += entry.is_regular_file();
  return n;
}

std::string payload(std::size_t n) {
  std::string text;
  for (std::size_t i = 0; i < n; ++i)
    text.push_back(static_cast<char>('a' + (i * 7 + i / 13) % 26));
  return text;
}

}  // namespace

// AWS's documented example (S3 GET Object with a Range header, 2013-05-24).
TEST(SigV4, MatchesTheAwsDocumentedGetObjectExample) {
  fetch::SigV4Request r;
  r.method = "GET";
  r.host = "examplebucket.s3.amazonaws.com";
  r.canonical_path = "/test.txt";
  r.payload_sha256 = "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855";
  r.amz_date = "20130524T000000Z";
  r.region = "us-east-1";
  r.extra_headers = {{"Range", "bytes=0-9"}};
  const auto signed_request =
      fetch::sign_v4(r, "AKIAIOSFODNN7EXAMPLE", "wJalrXUtnFEMI/K7MDENG/bPxRfiCYEXAMPLEKEY");
  ASSERT_TRUE(signed_request.ok()) << signed_request.error().message;
  const fetch::SigV4Result& s = signed_request.value();
  EXPECT_EQ(s.signature, "f0e8bdb87c964420e857bd35b5d6ed310bd44f0170aba48dd91039c6036bdb41");
  EXPECT_NE(s.authorization.find("SignedHeaders=host;range;x-amz-content-sha256;x-amz-date"),
            std::string::npos);
  EXPECT_EQ(s.authorization.find("wJalr"), std::string::npos) << "the secret is never sent";
}

TEST(SigV4, EncodesKeysOnceKeepingSlashes) {
  EXPECT_EQ(fetch::uri_encode("tiles/a b+c~d.las", true), "tiles/a%20b%2Bc~d.las");
  EXPECT_EQ(fetch::uri_encode("a/b", false), "a%2Fb");
}

TEST(FetchRequest, ParsesAndRefusesFragments) {
  fetch::Request r;
  const std::string sha(64, 'a');
  ASSERT_TRUE(fetch::parse_request("https://h/x.las#sha256=" + sha + "&size=12", r).ok());
  EXPECT_EQ(r.url, "https://h/x.las");
  EXPECT_EQ(r.sha256.value_or(""), sha);
  EXPECT_EQ(r.size.value_or(0), 12u);
  EXPECT_EQ(fetch::parse_request("https://h/x.las#sha256=xyz", r).code, ErrorCode::InputInvalid);
  EXPECT_EQ(fetch::parse_request("https://h/x.las#colour=red", r).code, ErrorCode::InputInvalid);
  EXPECT_TRUE(fetch::is_url("s3://bucket/key"));
  EXPECT_FALSE(fetch::is_url("config/examples/scenes/pavilion.json"));
  EXPECT_FALSE(fetch::is_url("/abs/path"));
}

class FetchFile : public ::testing::Test {
 protected:
  csgtile::test::TempDir tmp{"csgtile-fetch-"};
};

TEST_F(FetchFile, FileUrlIsVerifiedAndCached) {
  const std::string text = payload(5000);
  write_text(tmp.path() / "tile.las", text);
  const std::string url = "file://" + (tmp.path() / "tile.las").string();
  fetch::Request request{url, sha256_hex(text), text.size()};
  fetch::Result result;
  ASSERT_TRUE(fetch::fetch(request, {}, tmp.path() / "cache", result).ok());
  EXPECT_EQ(result.bytes, text.size());
  EXPECT_EQ(result.sha256, sha256_hex(text));
  EXPECT_EQ(result.path.filename(), "tile.las");
  EXPECT_EQ(file_text(result.path), text);
  EXPECT_FALSE(result.from_cache);
  fetch::Result again;
  ASSERT_TRUE(fetch::fetch(request, {}, tmp.path() / "cache", again).ok());
  EXPECT_TRUE(again.from_cache);
  EXPECT_EQ(again.path, result.path);

  request.sha256 = std::string(64, '0');
  fetch::Result wrong;
  const Failure f = fetch::fetch(request, {}, tmp.path() / "cache2", wrong);
  EXPECT_EQ(f.code, ErrorCode::FetchRefused) << f.message;
  EXPECT_NE(f.message.find("SHA-256"), std::string::npos) << f.message;
  EXPECT_EQ(regular_files(tmp.path() / "cache2"), 0u) << "nothing half-written";

  const Failure missing = fetch::fetch({"file://" + (tmp.path() / "nope.las").string(), {}, {}}, {},
                                       tmp.path() / "cache3", wrong);
  EXPECT_FALSE(missing.ok());
  EXPECT_NE(missing.message.find("nope.las"), std::string::npos) << missing.message;
}

TEST_F(FetchFile, SchemesOutsideThePolicyAreRefused) {
  fetch::Policy policy;
  policy.schemes = {"https", "s3"};
  fetch::Result result;
  Failure f = fetch::fetch({"file:///etc/hostname", {}, {}}, policy, tmp.path(), result);
  EXPECT_EQ(f.code, ErrorCode::FetchRefused);
  EXPECT_NE(f.message.find("scheme 'file' is not allowed"), std::string::npos) << f.message;
  f = fetch::fetch({"gopher://127.0.0.1/x", {}, {}}, {}, tmp.path(), result);
  EXPECT_EQ(f.code, ErrorCode::FetchRefused) << f.message;
  f = fetch::fetch({"http://user:hunter2@127.0.0.1:9/x", {}, {}}, {}, tmp.path(), result);
  EXPECT_EQ(f.code, ErrorCode::FetchRefused);
  EXPECT_EQ(f.message.find("hunter2"), std::string::npos)
      << "credentials never in messages: " << f.message;
  f = fetch::fetch({"http://127.0.0.1:9/x\r\nHost: evil", {}, {}}, {}, tmp.path(), result);
  EXPECT_EQ(f.code, ErrorCode::InputInvalid) << f.message;
}

class FetchHttp : public ::testing::Test {
 protected:
  void SetUp() override {
    write_text(tmp.path() / "tile.las", text);
    server = std::make_unique<BackgroundProcess>(
        "exec python3 " +
        quoted(fs::path(CSGTILE_SOURCE_DIR) / "tests/support/fault_http_server.py") + " " +
        quoted(tmp.path()));
    ASSERT_TRUE(server->running()) << server->problem();
    base = "http://127.0.0.1:" + server->first_line();
    policy.retry_delay_ms = 10;
    policy.connect_timeout_ms = 5000;
    policy.transfer_timeout_ms = 20000;
  }
  Failure get(const std::string& path, fetch::Result& result, const fetch::Policy& p) {
    return fetch::fetch({base + path, {}, {}}, p, tmp.path() / "cache", result);
  }
  Failure get(const std::string& path, fetch::Result& result) { return get(path, result, policy); }
  int requests(const std::string& path) {
    fetch::Result r;
    fetch::Policy p = policy;
    if (!fetch::fetch({base + "/counts", {}, {}}, p, tmp.path() / "counts", r).ok()) return -1;
    const auto counts = nlohmann::json::parse(file_text(r.path));
    return counts.value(path, 0);
  }

  csgtile::test::TempDir tmp{"csgtile-fetch-"};
  std::string text = payload(100000);
  std::unique_ptr<BackgroundProcess> server;
  std::string base;
  fetch::Policy policy;
};

TEST_F(FetchHttp, PlainAndChunkedBodies) {
  fetch::Result r;
  ASSERT_TRUE(get("/ok/tile.las", r).ok());
  EXPECT_EQ(file_text(r.path), text);
  EXPECT_EQ(r.attempts, 1);
  ASSERT_TRUE(get("/chunked/tile.las", r).ok());
  EXPECT_EQ(file_text(r.path), text);
}

TEST_F(FetchHttp, TransientFailuresAreRetried) {
  fetch::Result r;
  Failure f = get("/flaky/2/tile.las", r);
  ASSERT_TRUE(f.ok()) << f.message;
  EXPECT_EQ(r.attempts, 3);
  EXPECT_EQ(file_text(r.path), text);
  f = get("/reset/1/tile.las", r);
  ASSERT_TRUE(f.ok()) << f.message;
  EXPECT_EQ(r.attempts, 2);
  EXPECT_EQ(file_text(r.path), text);
  EXPECT_EQ(requests("/reset/1/tile.las"), 2);
}

TEST_F(FetchHttp, PersistentFailuresEndAsRetryableNetworkErrors) {
  fetch::Result r;
  Failure f = get("/flaky/10/tile.las", r);
  EXPECT_EQ(f.code, ErrorCode::Network) << f.message;
  EXPECT_NE(f.message.find("HTTP 503"), std::string::npos) << f.message;
  EXPECT_NE(f.message.find("after 3 attempts"), std::string::npos) << f.message;
  EXPECT_EQ(requests("/flaky/10/tile.las"), 3);
  EXPECT_TRUE(error_info(f.code).retryable);

  f = get("/truncate/tile.las", r);
  EXPECT_EQ(f.code, ErrorCode::Network) << f.message;

  fetch::Policy slow = policy;
  slow.attempts = 1;
  slow.low_speed_bytes_per_second = 1000;
  slow.low_speed_seconds = 1;
  f = get("/slow/tile.las", r, slow);
  EXPECT_EQ(f.code, ErrorCode::Network) << f.message;
  EXPECT_EQ(regular_files(tmp.path() / "cache"), 0u) << "no partial download left behind";
}

TEST_F(FetchHttp, ClientErrorsAreNotRetried) {
  fetch::Result r;
  const Failure f = get("/status/404", r);
  EXPECT_EQ(f.code, ErrorCode::FetchRefused) << f.message;
  EXPECT_NE(f.message.find("HTTP 404"), std::string::npos) << f.message;
  EXPECT_EQ(requests("/status/404"), 1);
  EXPECT_FALSE(error_info(f.code).retryable);
}

TEST_F(FetchHttp, RedirectsAreBoundedAndRechecked) {
  fetch::Result r;
  Failure f = get("/redirect/2/tile.las", r);
  ASSERT_TRUE(f.ok()) << f.message;
  EXPECT_EQ(file_text(r.path), text);
  f = get("/loop", r);
  EXPECT_EQ(f.code, ErrorCode::FetchRefused) << f.message;
  EXPECT_NE(f.message.find("redirects"), std::string::npos) << f.message;
  f = get("/to/http%3A%2F%2F169.254.169.254%2Flatest%2Fmeta-data", r);
  EXPECT_EQ(f.code, ErrorCode::FetchRefused) << f.message;
  EXPECT_NE(f.message.find("169.254.169.254"), std::string::npos) << f.message;
  f = get("/to/file%3A%2F%2F%2Fetc%2Fpasswd", r);
  EXPECT_EQ(f.code, ErrorCode::FetchRefused) << f.message;
  EXPECT_EQ(regular_files(tmp.path() / "cache"), 1u) << "only the one good download";
}

TEST_F(FetchHttp, SizeCapHoldsWithAndWithoutContentLength) {
  fetch::Policy capped = policy;
  capped.max_bytes = 50000;
  fetch::Result r;
  Failure f = get("/ok/tile.las", r, capped);
  EXPECT_EQ(f.code, ErrorCode::FetchRefused) << f.message;
  EXPECT_NE(f.message.find("size cap"), std::string::npos) << f.message;
  f = get("/chunked/tile.las", r, capped);
  EXPECT_EQ(f.code, ErrorCode::FetchRefused) << f.message;
  f = get("/huge", r, capped);
  EXPECT_EQ(f.code, ErrorCode::FetchRefused) << f.message;
  f = get("/endless", r, capped);
  EXPECT_EQ(f.code, ErrorCode::FetchRefused) << f.message;
  EXPECT_EQ(regular_files(tmp.path() / "cache"), 0u);
}

// ---- S3 against a server that verifies signatures -----------------------------------------

class FetchS3 : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string missing;
    server = csgtile::test::start_s3rver(tmp.path() / "s3", "tiles", missing);
    if (!server && csgtile::test::s3rver_required()) FAIL() << missing;
    if (!server) GTEST_SKIP() << missing;
    ASSERT_TRUE(server->running()) << server->problem();
    policy.s3.endpoint = "http://127.0.0.1:" + server->first_line();
    policy.retry_delay_ms = 10;
  }
  csgtile::test::TempDir tmp{"csgtile-fetch-"};
  std::unique_ptr<BackgroundProcess> server;
  fetch::Policy policy;
};

TEST_F(FetchS3, SignedPutThenGetRoundTrips) {
  ScopedEnv env({{"AWS_ACCESS_KEY_ID", "S3RVER"}, {"AWS_SECRET_ACCESS_KEY", "S3RVER"}});
  const std::string text = payload(70000);
  Failure f = fetch::s3_put("s3://tiles/city/a b/tile+1.las", text, policy);
  ASSERT_TRUE(f.ok()) << f.message;
  fetch::Result r;
  f = fetch::fetch({"s3://tiles/city/a b/tile+1.las", sha256_hex(text), text.size()}, policy,
                   tmp.path() / "cache", r);
  ASSERT_TRUE(f.ok()) << f.message;
  EXPECT_EQ(file_text(r.path), text);

  f = fetch::fetch({"s3://tiles/city/missing.las", {}, {}}, policy, tmp.path() / "cache", r);
  EXPECT_EQ(f.code, ErrorCode::FetchRefused) << f.message;
  EXPECT_NE(f.message.find("HTTP 404"), std::string::npos) << f.message;
}

TEST_F(FetchS3, AWrongSecretIsRefusedAndNeverShown) {
  {
    ScopedEnv env({{"AWS_ACCESS_KEY_ID", "S3RVER"}, {"AWS_SECRET_ACCESS_KEY", "S3RVER"}});
    ASSERT_TRUE(fetch::s3_put("s3://tiles/t.las", "points", policy).ok());
  }
  ScopedEnv env({{"AWS_ACCESS_KEY_ID", "S3RVER"}, {"AWS_SECRET_ACCESS_KEY", "not-the-secret"}});
  fetch::Result r;
  const Failure f = fetch::fetch({"s3://tiles/t.las", {}, {}}, policy, tmp.path() / "cache", r);
  EXPECT_EQ(f.code, ErrorCode::FetchRefused) << f.message;
  EXPECT_NE(f.message.find("HTTP 403"), std::string::npos) << f.message;
  EXPECT_EQ(f.message.find("not-the-secret"), std::string::npos) << f.message;
  EXPECT_EQ(regular_files(tmp.path() / "cache"), 0u);
  EXPECT_EQ(fetch::s3_put("s3://tiles/u.las", "points", policy).code, ErrorCode::FetchRefused);
}

TEST_F(FetchS3, CredentialsComeFromAFileWhenNotInTheEnvironment) {
  write_text(tmp.path() / "credentials",
             "[default]\naws_access_key_id = nobody\naws_secret_access_key = x\n"
             "[csgtile]\naws_access_key_id = S3RVER\naws_secret_access_key = S3RVER\n");
  ScopedEnv env({{"AWS_ACCESS_KEY_ID", ""},
                 {"AWS_SECRET_ACCESS_KEY", ""},
                 {"AWS_SHARED_CREDENTIALS_FILE", (tmp.path() / "credentials").string()},
                 {"AWS_PROFILE", "csgtile"}});
  ASSERT_TRUE(fetch::s3_put("s3://tiles/p.las", "profile", policy).ok());
  fetch::Result r;
  ASSERT_TRUE(fetch::fetch({"s3://tiles/p.las", {}, {}}, policy, tmp.path() / "cache", r).ok());
  EXPECT_EQ(file_text(r.path), "profile");
}

TEST_F(FetchS3, UnsafeKeysAndBucketsAreRefusedBeforeAnyRequest) {
  ScopedEnv env({{"AWS_ACCESS_KEY_ID", "S3RVER"}, {"AWS_SECRET_ACCESS_KEY", "S3RVER"}});
  fetch::Result r;
  for (const std::string url :
       {"s3://tiles/a/../b.las", "s3://tiles//b.las", "s3://tiles/", "s3://T!/x.las"}) {
    const Failure f = fetch::fetch({url, {}, {}}, policy, tmp.path() / "cache", r);
    EXPECT_EQ(f.code, ErrorCode::InputInvalid) << url << ": " << f.message;
  }
}
