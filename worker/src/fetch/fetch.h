#pragma once
/// \file
/// Fetching inputs with libcurl (internal to the worker): `file://`, `http://`, `https://`
/// and `s3://` (AWS Signature V4) into a local cache, verified, under a policy.
///
/// Safety: only allowed schemes; redirects followed one by one (each target re-checked,
/// at most `max_redirects`, never to another scheme than http/https); connections to
/// link-local, multicast or unspecified addresses refused (cloud metadata endpoints live
/// there), loopback and private ranges allowed; TLS peer and host verification always on;
/// a size cap counted as bytes arrive; connect/transfer timeouts and a low-speed abort.
/// Credentials come from the environment or a credentials file and never appear in
/// messages; user:password in a URL is refused. A download lands in the cache through a
/// temporary file and a rename, after its size and (when given) SHA-256 check out.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "csgtile/geo/byte_source.h"
#include "csgtile/geo/las.h"
#include "csgtile/worker/errors.h"

namespace csgtile::worker::fetch {

/// Where `s3://bucket/key` goes: path-style `<endpoint>/<bucket>/<key>`.
struct S3Settings {
  std::string endpoint;  ///< "http://127.0.0.1:4569"; empty → https://s3.<region>.amazonaws.com
  std::string region = "us-east-1";
};

struct Policy {
  std::vector<std::string> schemes{"file", "http", "https", "s3"};
  long connect_timeout_ms = 10'000;
  long transfer_timeout_ms = 600'000;
  long low_speed_bytes_per_second = 1024;  ///< abort when slower than this ...
  long low_speed_seconds = 30;             ///< ... for this long
  std::uint64_t max_bytes = 8ull << 30;
  int max_redirects = 5;
  int attempts = 3;           ///< tries per fetch for transient failures (resets, 5xx, timeouts)
  long retry_delay_ms = 200;  ///< first back-off; doubled per attempt
  std::string ca_bundle;      ///< CA file; empty → the system's
  S3Settings s3;
};

/// An input reference: a URL and what the download must match. The optional fragment
/// `#sha256=<64 hex>` (and/or `size=<bytes>`, joined by '&') sets them; it is never sent.
struct Request {
  std::string url;
  std::optional<std::string> sha256;
  std::optional<std::uint64_t> size;
};

/// Splits "URL#sha256=..&size=.." into a Request; a malformed fragment is an InputInvalid.
Failure parse_request(const std::string& text, Request& request);

/// True when `text` names a URL (has a "scheme://" prefix) rather than a local path.
bool is_url(const std::string& text);

struct Result {
  std::filesystem::path path;  ///< the cached file
  std::uint64_t bytes = 0;
  std::string sha256;       ///< lower-case hex of the content
  bool from_cache = false;  ///< an earlier verified download was reused
  int attempts = 0;         ///< transfer attempts made
};

/// Fetches `request` into `cache_dir` (created when missing). A verified cached copy is
/// reused only when the request names its SHA-256. Errors name the URL (without
/// credentials) and the cause; transient failures that outlast the retries are Network
/// (retryable), policy refusals, HTTP 4xx and verification failures FetchRefused/InputInvalid.
Failure fetch(const Request& request, const Policy& policy, const std::filesystem::path& cache_dir,
              Result& result);

/// Uploads `bytes` to `s3://bucket/key` with a signed PUT (the payload's SHA-256 signed
/// too). Transient failures (resets, timeouts, 5xx, 429) are retried as fetch retries them
/// (`policy.attempts`, doubling `policy.retry_delay_ms`) and end as Network; refusals (4xx,
/// e.g. 403 for a wrong secret) are FetchRefused at once; a malformed URL or key InputInvalid.
Failure s3_put(const std::string& url, std::string_view bytes, const Policy& policy);

/// What a signed HEAD or GET found at `s3://bucket/key`.
struct S3Object {
  bool exists = false;     ///< false when S3 answered 404 (not an error)
  std::uint64_t size = 0;  ///< the object's length in bytes when it exists
};

/// Signed HEAD of `s3://bucket/key`: whether the object exists and its size. A missing
/// object is `exists == false`, not an error; other errors and retries as for s3_put.
Failure s3_head(const std::string& url, const Policy& policy, S3Object& object);

/// Signed GET of `s3://bucket/key` into memory (for small objects: manifests, pointers),
/// at most `policy.max_bytes` (more is FetchRefused). A missing object is
/// `exists == false` with `bytes` empty; other errors and retries as for s3_put.
Failure s3_get(const std::string& url, const Policy& policy, S3Object& object, std::string& bytes);

/// S3 credentials: AWS_ACCESS_KEY_ID / AWS_SECRET_ACCESS_KEY (/ AWS_SESSION_TOKEN) from
/// the environment, else the [AWS_PROFILE or default] section of AWS_SHARED_CREDENTIALS_FILE
/// (default ~/.aws/credentials). Empty keys when none is found.
struct Credentials {
  std::string access_key;
  std::string secret_key;
  std::string session_token;
};
Credentials s3_credentials();

/// Requests and bytes a range source fetched (for reports and benches).
struct RangeStats {
  std::uint64_t requests = 0;
  std::uint64_t bytes = 0;
  /// The transfer failure behind the reader's last IoError (Network stays retryable for the
  /// job that reads; the reader itself only sees an I/O error).
  Failure last_failure;
};

/// Opens an http(s):// or s3:// object for random access by HTTP range requests, as a
/// geo::ByteSource for the LAS/LAZ/COPC reader: only what the reader reads is fetched (a COPC
/// region query: header, VLRs, chunk table, hierarchy pages and the nodes' chunks). The first
/// request asks for the first 16 KiB (header and VLRs) and learns the size from
/// Content-Range; reads smaller than `block_bytes` (at most 1/16 of the object) are served
/// from aligned blocks of that size (a few kept), larger ones fetched exactly.
/// A server that ignores Range (HTTP 200) sends the whole object, which is then served from
/// memory (at most policy.max_bytes). Same policy as fetch(): schemes, address rules, TLS,
/// timeouts, retries of transient failures, redirects one by one, S3 signed per request.
/// Errors: as fetch(); a read that fails later is an IoError of the reader naming the range.
/// True for a URL that is read remotely (http, https, s3): any URL but file://.
bool is_remote_url(const std::string& text);

/// Opens a LAS/LAZ/COPC input: a path (or file:// URL) in place, an http(s)/s3 URL by range
/// requests (`stats` counts them). Errors: as open_range_source and the reader's.
Failure open_las(const std::string& input, const Policy& policy,
                 std::unique_ptr<geo::LasReader>& reader,
                 std::shared_ptr<RangeStats> stats = nullptr);

Failure open_range_source(const std::string& url, const Policy& policy,
                          std::unique_ptr<geo::ByteSource>& source,
                          std::shared_ptr<RangeStats> stats = nullptr,
                          std::uint64_t block_bytes = 64 * 1024);

}  // namespace csgtile::worker::fetch
