#include "fetch/fetch.h"

#include <arpa/inet.h>
#include <curl/curl.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <mutex>
#include <thread>

#include "csgtile/worker/files.h"
#include "fetch/sigv4.h"
#include "fetch/transport.h"

#ifndef CSGTILE_VERSION
#define CSGTILE_VERSION "dev"
#endif

namespace csgtile::worker::fetch {
namespace {

void global_init() {
  static std::once_flag once;
  std::call_once(once, [] { curl_global_init(CURL_GLOBAL_DEFAULT); });
}

std::string lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return text;
}

bool is_hex64(const std::string& text) {
  return text.size() == 64 && std::all_of(text.begin(), text.end(), [](unsigned char c) {
           return std::isdigit(c) || (c >= 'a' && c <= 'f');
         });
}

// ---- URL parts (libcurl's URL API) ------------------------------------------------------

struct UrlParts {
  std::string scheme, user, password, host, port, path, query;
};

struct UrlHandle {
  CURLU* h = curl_url();
  ~UrlHandle() { curl_url_cleanup(h); }
  std::string get(CURLUPart part, unsigned flags = 0) const {
    char* text = nullptr;
    if (curl_url_get(h, part, &text, flags) != CURLUE_OK || text == nullptr) return {};
    std::string out = text;
    curl_free(text);
    return out;
  }
};

bool split_url(const std::string& url, UrlParts& parts) {
  UrlHandle u;
  if (u.h == nullptr) return false;
  if (curl_url_set(u.h, CURLUPART_URL, url.c_str(),
                   CURLU_NON_SUPPORT_SCHEME | CURLU_PATH_AS_IS | CURLU_ALLOW_SPACE) != CURLUE_OK)
    return false;
  parts.scheme = lower(u.get(CURLUPART_SCHEME));
  parts.user = u.get(CURLUPART_USER);
  parts.password = u.get(CURLUPART_PASSWORD);
  parts.host = u.get(CURLUPART_HOST);
  parts.port = u.get(CURLUPART_PORT);
  parts.path = u.get(CURLUPART_PATH, CURLU_URLDECODE);
  parts.query = u.get(CURLUPART_QUERY);
  return true;
}

// The URL as it may appear in messages and logs: no user info, no query (presigned URLs
// carry their signature there), no fragment.
std::string redacted(const std::string& url) {
  UrlParts p;
  if (!split_url(url, p)) {
    const std::size_t cut = url.find_first_of("?#@");
    return cut == std::string::npos ? url : url.substr(0, cut) + "…";
  }
  std::string out = p.scheme + "://" + p.host;
  if (!p.port.empty()) out += ":" + p.port;
  out += p.path;
  if (!p.query.empty()) out += "?…";
  return out;
}

bool has_control(const std::string& text) {
  return std::any_of(text.begin(), text.end(),
                     [](unsigned char c) { return c < 0x20 || c == 0x7f; });
}

// ---- address policy (opensocket callback) -----------------------------------------------

bool refused_v4(std::uint32_t a) {             // host byte order
  return (a >> 24) == 0 ||                     // 0.0.0.0/8 "this network"
         (a >> 16) == ((169u << 8) | 254u) ||  // 169.254.0.0/16 link-local (metadata)
         (a >> 28) == 0xE ||                   // 224.0.0.0/4 multicast
         a == 0xFFFFFFFFu;                     // broadcast
}

std::string describe_refusal(const curl_sockaddr* address) {
  char text[INET6_ADDRSTRLEN] = "?";
  if (address->family == AF_INET) {
    const auto* in = reinterpret_cast<const sockaddr_in*>(&address->addr);
    inet_ntop(AF_INET, &in->sin_addr, text, sizeof text);
  } else if (address->family == AF_INET6) {
    const auto* in6 = reinterpret_cast<const sockaddr_in6*>(&address->addr);
    inet_ntop(AF_INET6, &in6->sin6_addr, text, sizeof text);
  }
  return text;
}

bool address_refused(const curl_sockaddr* address) {
  if (address->family == AF_INET) {
    const auto* in = reinterpret_cast<const sockaddr_in*>(&address->addr);
    return refused_v4(ntohl(in->sin_addr.s_addr));
  }
  if (address->family == AF_INET6) {
    const auto* in6 = reinterpret_cast<const sockaddr_in6*>(&address->addr);
    const unsigned char* b = in6->sin6_addr.s6_addr;
    if (IN6_IS_ADDR_UNSPECIFIED(&in6->sin6_addr) || IN6_IS_ADDR_LINKLOCAL(&in6->sin6_addr) ||
        IN6_IS_ADDR_MULTICAST(&in6->sin6_addr)) {
      return true;
    }
    if (IN6_IS_ADDR_V4MAPPED(&in6->sin6_addr)) {
      const std::uint32_t a = (std::uint32_t{b[12]} << 24) | (std::uint32_t{b[13]} << 16) |
                              (std::uint32_t{b[14]} << 8) | std::uint32_t{b[15]};
      return refused_v4(a);
    }
    return false;
  }
  return address->family != AF_UNIX;
}

// ---- one transfer ------------------------------------------------------------------------

struct Sink {
  std::FILE* file = nullptr;
  Sha256 sha;
  std::uint64_t bytes = 0;
  std::uint64_t cap = 0;
  bool over_cap = false;
  bool write_failed = false;
  std::string refused_address;

  void reset() {
    std::rewind(file);
    if (ftruncate(fileno(file), 0) != 0) write_failed = true;
    sha.reset();
    bytes = 0;
    over_cap = false;
  }
};

std::size_t on_write(char* data, std::size_t size, std::size_t count, void* user) {
  auto* sink = static_cast<Sink*>(user);
  const std::size_t n = size * count;
  if (sink->bytes + n > sink->cap) {
    sink->over_cap = true;
    return 0;  // aborts the transfer (CURLE_WRITE_ERROR)
  }
  if (std::fwrite(data, 1, n, sink->file) != n) {
    sink->write_failed = true;
    return 0;
  }
  sink->sha.update({data, n});
  sink->bytes += n;
  return n;
}

curl_socket_t on_open_socket(void* user, curlsocktype, curl_sockaddr* address) {
  auto* refused = static_cast<std::string*>(user);
  if (address_refused(address)) {
    *refused = describe_refusal(address);
    return CURL_SOCKET_BAD;
  }
  return ::socket(address->family, address->socktype, address->protocol);
}

struct CurlDeleter {
  void operator()(CURL* c) const { curl_easy_cleanup(c); }
};
struct SlistDeleter {
  void operator()(curl_slist* l) const { curl_slist_free_all(l); }
};

enum class Outcome { Done, Redirect, Transient, Permanent };

struct Attempt {
  Outcome outcome = Outcome::Permanent;
  Failure failure;
  std::string location;  ///< absolute redirect target
};

bool transient_curl(CURLcode code) {
  switch (code) {
    case CURLE_COULDNT_CONNECT:
    case CURLE_OPERATION_TIMEDOUT:
    case CURLE_RECV_ERROR:
    case CURLE_SEND_ERROR:
    case CURLE_PARTIAL_FILE:
    case CURLE_GOT_NOTHING:
    case CURLE_HTTP2:
    case CURLE_HTTP2_STREAM:
    case CURLE_COULDNT_RESOLVE_HOST:
      return true;
    default:
      return false;
  }
}

// Options every transfer shares: no redirects followed by libcurl, the path as given (it is
// what S3 signed), timeouts, TLS verification, the address policy and the error text.
void set_common_options(CURL* c, const Policy& policy, std::string& refused_address,
                        char* error_text) {
  curl_easy_setopt(c, CURLOPT_FOLLOWLOCATION, 0L);
  curl_easy_setopt(c, CURLOPT_PATH_AS_IS, 1L);
  curl_easy_setopt(c, CURLOPT_NOSIGNAL, 1L);
  curl_easy_setopt(c, CURLOPT_CONNECTTIMEOUT_MS, policy.connect_timeout_ms);
  curl_easy_setopt(c, CURLOPT_TIMEOUT_MS, policy.transfer_timeout_ms);
  curl_easy_setopt(c, CURLOPT_SSL_VERIFYPEER, 1L);
  curl_easy_setopt(c, CURLOPT_SSL_VERIFYHOST, 2L);
  if (!policy.ca_bundle.empty()) curl_easy_setopt(c, CURLOPT_CAINFO, policy.ca_bundle.c_str());
  curl_easy_setopt(c, CURLOPT_USERAGENT, "csgtile/" CSGTILE_VERSION);
  curl_easy_setopt(c, CURLOPT_ERRORBUFFER, error_text);
  curl_easy_setopt(c, CURLOPT_OPENSOCKETFUNCTION, on_open_socket);
  curl_easy_setopt(c, CURLOPT_OPENSOCKETDATA, &refused_address);
}

Attempt transfer_once(const std::string& url, const std::vector<std::string>& headers,
                      const Policy& policy, const std::string& allowed_protocols, Sink& sink) {
  Attempt attempt;
  std::unique_ptr<CURL, CurlDeleter> curl(curl_easy_init());
  if (!curl) {
    attempt.failure = {ErrorCode::Internal, "libcurl could not create a handle"};
    return attempt;
  }
  CURL* c = curl.get();
  char error_text[CURL_ERROR_SIZE] = "";
  std::unique_ptr<curl_slist, SlistDeleter> list;
  for (const std::string& h : headers) {
    curl_slist* grown = curl_slist_append(list.get(), h.c_str());
    if (grown == nullptr) {
      attempt.failure = {ErrorCode::Internal, "libcurl could not build the request headers"};
      return attempt;
    }
    static_cast<void>(list.release());  // owned by the list curl_slist_append returned
    list.reset(grown);
  }
  set_common_options(c, policy, sink.refused_address, error_text);
  curl_easy_setopt(c, CURLOPT_URL, url.c_str());
  curl_easy_setopt(c, CURLOPT_PROTOCOLS_STR, allowed_protocols.c_str());
  curl_easy_setopt(c, CURLOPT_LOW_SPEED_LIMIT, policy.low_speed_bytes_per_second);
  curl_easy_setopt(c, CURLOPT_LOW_SPEED_TIME, policy.low_speed_seconds);
  curl_easy_setopt(c, CURLOPT_MAXFILESIZE_LARGE, static_cast<curl_off_t>(policy.max_bytes));
  curl_easy_setopt(c, CURLOPT_WRITEFUNCTION, on_write);
  curl_easy_setopt(c, CURLOPT_WRITEDATA, &sink);
  if (list) curl_easy_setopt(c, CURLOPT_HTTPHEADER, list.get());

  const CURLcode code = curl_easy_perform(c);
  const std::string where = redacted(url);
  if (!sink.refused_address.empty()) {
    attempt.failure = {
        ErrorCode::FetchRefused,
        where + ": connection to " + sink.refused_address +
            " refused (link-local, multicast and unspecified addresses are never fetched)"};
    return attempt;
  }
  if (sink.over_cap || code == CURLE_FILESIZE_EXCEEDED) {
    attempt.failure = {ErrorCode::FetchRefused, where + ": larger than the size cap of " +
                                                    std::to_string(policy.max_bytes) + " bytes"};
    return attempt;
  }
  if (sink.write_failed) {
    attempt.failure = {ErrorCode::Io, where + ": cannot write the download to the cache"};
    return attempt;
  }
  if (code != CURLE_OK) {
    const std::string detail = error_text[0] != '\0' ? error_text : curl_easy_strerror(code);
    attempt.outcome = transient_curl(code) ? Outcome::Transient : Outcome::Permanent;
    const ErrorCode kind = attempt.outcome == Outcome::Transient  ? ErrorCode::Network
                           : code == CURLE_UNSUPPORTED_PROTOCOL   ? ErrorCode::FetchRefused
                           : code == CURLE_FILE_COULDNT_READ_FILE ? ErrorCode::InputInvalid
                           : code == CURLE_URL_MALFORMAT          ? ErrorCode::InputInvalid
                                                                  : ErrorCode::Network;
    attempt.failure = {kind, where + ": " + detail};
    // TLS and other non-transient transport errors are not worth retrying in this fetch,
    // but the job may still be retried later (Network is retryable).
    return attempt;
  }
  long status = 0;
  curl_easy_getinfo(c, CURLINFO_RESPONSE_CODE, &status);
  if (status == 0 || (status >= 200 && status < 300)) {
    attempt.outcome = Outcome::Done;
    return attempt;
  }
  if (status == 301 || status == 302 || status == 303 || status == 307 || status == 308) {
    char* location = nullptr;
    curl_easy_getinfo(c, CURLINFO_REDIRECT_URL, &location);
    if (location == nullptr) {
      attempt.failure = {ErrorCode::FetchRefused,
                         where + ": HTTP " + std::to_string(status) + " without a Location"};
      return attempt;
    }
    attempt.outcome = Outcome::Redirect;
    attempt.location = location;
    return attempt;
  }
  const bool transient = status >= 500 || status == 429 || status == 408;
  attempt.outcome = transient ? Outcome::Transient : Outcome::Permanent;
  attempt.failure = {transient ? ErrorCode::Network : ErrorCode::FetchRefused,
                     where + ": HTTP " + std::to_string(status)};
  return attempt;
}

// ---- S3 ------------------------------------------------------------------------------------

bool valid_bucket(const std::string& bucket) {
  if (bucket.size() < 3 || bucket.size() > 63) return false;
  return std::all_of(bucket.begin(), bucket.end(), [](unsigned char c) {
    return std::islower(c) || std::isdigit(c) || c == '-' || c == '.';
  });
}

bool valid_key(const std::string& key) {
  if (key.empty() || key.front() == '/' || has_control(key)) return false;
  std::size_t start = 0;
  while (start <= key.size()) {
    const std::size_t end = std::min(key.find('/', start), key.size());
    const std::string segment = key.substr(start, end - start);
    if (segment.empty() || segment == "." || segment == "..") return false;
    start = end + 1;
  }
  return true;
}

struct S3Target {
  std::string url;
  std::vector<std::string> headers;
};

Failure s3_target(const UrlParts& parts, const std::string& original, const Policy& policy,
                  const std::string& method, const std::string& payload_sha256, S3Target& target) {
  const std::string bucket = parts.host;
  const std::string key = parts.path.empty() ? std::string() : parts.path.substr(1);
  if (!valid_bucket(bucket)) {
    return {ErrorCode::InputInvalid, redacted(original) + ": not a valid S3 bucket name"};
  }
  if (!valid_key(key)) {
    return {ErrorCode::InputInvalid,
            redacted(original) +
                ": not a valid S3 key (empty, '.', '..' or empty segments, or control characters)"};
  }
  std::string endpoint = policy.s3.endpoint;
  if (endpoint.empty()) endpoint = "https://s3." + policy.s3.region + ".amazonaws.com";
  UrlParts ep;
  if (!split_url(endpoint, ep) || (ep.scheme != "http" && ep.scheme != "https") ||
      ep.host.empty()) {
    return {ErrorCode::ConfigInvalid, "S3 endpoint " + endpoint + " is not an http(s) URL"};
  }
  const Credentials credentials = s3_credentials();
  if (credentials.access_key.empty() || credentials.secret_key.empty()) {
    return {ErrorCode::FetchRefused,
            redacted(original) +
                ": no S3 credentials (set AWS_ACCESS_KEY_ID and AWS_SECRET_ACCESS_KEY, "
                "or AWS_SHARED_CREDENTIALS_FILE)"};
  }
  const std::string host = ep.port.empty() ? ep.host : ep.host + ":" + ep.port;
  SigV4Request request;
  request.method = method;
  request.host = host;
  request.canonical_path = "/" + bucket + "/" + uri_encode(key, true);
  request.payload_sha256 = payload_sha256;
  request.amz_date = amz_date_now();
  request.region = policy.s3.region;
  if (!credentials.session_token.empty()) {
    request.extra_headers.emplace_back("x-amz-security-token", credentials.session_token);
  }
  auto signature = sign_v4(request, credentials.access_key, credentials.secret_key);
  if (!signature.ok()) {
    return {signature.error().code,
            "cannot sign the request to " + host + ": " + signature.error().message};
  }
  target.url = ep.scheme + "://" + host + request.canonical_path;
  target.headers = std::move(signature).value().headers;
  return {};
}

std::string safe_file_name(const std::string& path) {
  std::string name = path.substr(path.find_last_of('/') + 1);
  for (char& ch : name) {
    const auto c = static_cast<unsigned char>(ch);
    if (!(std::isalnum(c) || c == '.' || c == '_' || c == '-')) ch = '_';
  }
  if (name.empty() || name == "." || name == "..") name = "download";
  return name;
}

}  // namespace

namespace transport {

void init() { global_init(); }
std::string redact(const std::string& url) { return redacted(url); }
void set_options(CURL* c, const Policy& policy, std::string& refused_address, char* error_text) {
  set_common_options(c, policy, refused_address, error_text);
}
bool transient(CURLcode code) { return transient_curl(code); }

Failure resolve(const std::string& text, const Policy& policy, bool allow_file, Target& target) {
  const std::string where = redacted(text);
  if (has_control(text))
    return {ErrorCode::InputInvalid, where + ": control characters in the URL"};
  UrlParts parts;
  if (!split_url(text, parts)) return {ErrorCode::InputInvalid, where + ": not a valid URL"};
  if (std::find(policy.schemes.begin(), policy.schemes.end(), parts.scheme) ==
      policy.schemes.end()) {
    std::string allowed;
    for (const std::string& s : policy.schemes) allowed += (allowed.empty() ? "" : ", ") + s;
    return {ErrorCode::FetchRefused,
            where + ": scheme '" + parts.scheme + "' is not allowed (allowed: " + allowed + ")"};
  }
  if (!parts.user.empty() || !parts.password.empty()) {
    return {
        ErrorCode::FetchRefused,
        where + ": credentials in the URL are refused (use the environment or a credentials file)"};
  }
  target = {};
  target.path = parts.path;
  target.s3 = parts.scheme == "s3";
  if (target.s3) {
    S3Target signed_target;
    if (Failure f = s3_target(parts, text, policy, "GET", sha256_hex(""), signed_target); !f.ok()) {
      return f;
    }
    target.url = signed_target.url;
    target.headers = signed_target.headers;
    target.protocols = "http,https";
    return {};
  }
  if (parts.scheme != "http" && parts.scheme != "https" &&
      !(allow_file && parts.scheme == "file")) {
    return {ErrorCode::FetchRefused,
            where + ": scheme '" + parts.scheme + "' is not supported" +
                (allow_file ? "" : " for range requests (http, https, s3)")};
  }
  target.url = text.substr(0, text.find('#'));
  target.protocols = parts.scheme;
  return {};
}

Failure redirect_target(const std::string& where, const std::string& location, const Policy& policy,
                        Target& target) {
  UrlParts next;
  if (!split_url(location, next) || (next.scheme != "http" && next.scheme != "https") ||
      std::find(policy.schemes.begin(), policy.schemes.end(), next.scheme) ==
          policy.schemes.end()) {
    return {ErrorCode::FetchRefused, where + ": redirect to " + redacted(location) +
                                         " refused (only allowed http(s) targets)"};
  }
  UrlParts current;
  split_url(target.url, current);
  if (current.scheme == "https" && next.scheme == "http") {
    return {ErrorCode::FetchRefused,
            where + ": redirect from https to plain http (" + redacted(location) + ") refused"};
  }
  if (!next.user.empty() || !next.password.empty()) {
    return {ErrorCode::FetchRefused, where + ": redirect to a URL with credentials refused"};
  }
  target.url = location;
  target.protocols = next.scheme;
  return {};
}

}  // namespace transport

bool is_url(const std::string& text) {
  const std::size_t colon = text.find("://");
  if (colon == std::string::npos || colon == 0) return false;
  return std::all_of(
      text.begin(), text.begin() + static_cast<std::ptrdiff_t>(colon),
      [](unsigned char c) { return std::isalnum(c) || c == '+' || c == '-' || c == '.'; });
}

Failure parse_request(const std::string& text, Request& request) {
  request = {};
  const std::size_t hash = text.find('#');
  request.url = text.substr(0, hash);
  if (hash == std::string::npos) return {};
  const std::string fragment = text.substr(hash + 1);
  std::size_t start = 0;
  while (start <= fragment.size()) {
    const std::size_t end = std::min(fragment.find('&', start), fragment.size());
    const std::string item = fragment.substr(start, end - start);
    const std::size_t eq = item.find('=');
    const std::string name = item.substr(0, eq);
    const std::string value = eq == std::string::npos ? std::string() : item.substr(eq + 1);
    if (name == "sha256" && is_hex64(lower(value))) {
      request.sha256 = lower(value);
    } else if (name == "size" && !value.empty() && value.size() <= 19 &&
               std::all_of(value.begin(), value.end(),
                           [](unsigned char c) { return std::isdigit(c); })) {
      request.size = std::stoull(value);
    } else {
      return {ErrorCode::InputInvalid,
              redacted(request.url) + ": bad fragment item '" + item +
                  "' (expected sha256=<64 hex digits> or size=<bytes>, joined by '&')"};
    }
    start = end + 1;
  }
  return {};
}

Credentials s3_credentials() {
  Credentials c;
  auto env = [](const char* name) {
    // The environment is read, never set, once the worker runs.
    const char* value = std::getenv(name);  // NOLINT(concurrency-mt-unsafe)
    return value != nullptr ? std::string(value) : std::string();
  };
  c.access_key = env("AWS_ACCESS_KEY_ID");
  c.secret_key = env("AWS_SECRET_ACCESS_KEY");
  c.session_token = env("AWS_SESSION_TOKEN");
  if (!c.access_key.empty() && !c.secret_key.empty()) return c;
  c = {};
  std::string file = env("AWS_SHARED_CREDENTIALS_FILE");
  if (file.empty() && !env("HOME").empty()) file = env("HOME") + "/.aws/credentials";
  std::string profile = env("AWS_PROFILE");
  if (profile.empty()) profile = "default";
  std::ifstream in(file);
  std::string line;
  bool in_profile = false;
  auto trim = [](const std::string& s) {
    const std::size_t b = s.find_first_not_of(" \t\r");
    const std::size_t e = s.find_last_not_of(" \t\r");
    return b == std::string::npos ? std::string() : s.substr(b, e - b + 1);
  };
  while (std::getline(in, line)) {
    line = trim(line);
    if (line.empty() || line[0] == '#' || line[0] == ';') continue;
    if (line.front() == '[' && line.back() == ']') {
      in_profile = trim(line.substr(1, line.size() - 2)) == profile;
      continue;
    }
    if (!in_profile) continue;
    const std::size_t eq = line.find('=');
    if (eq == std::string::npos) continue;
    const std::string name = trim(line.substr(0, eq));
    const std::string value = trim(line.substr(eq + 1));
    if (name == "aws_access_key_id") c.access_key = value;
    if (name == "aws_secret_access_key") c.secret_key = value;
    if (name == "aws_session_token") c.session_token = value;
  }
  return c;
}

Failure fetch(const Request& request, const Policy& policy, const std::filesystem::path& cache_dir,
              Result& result) {
  global_init();
  result = {};
  const std::string where = redacted(request.url);
  transport::Target target;
  if (Failure f = transport::resolve(request.url, policy, true, target); !f.ok()) return f;

  // The cache slot: a directory per URL (by its hash), the file keeps the URL's name so that
  // readers that go by extension see it.
  const std::filesystem::path dir =
      cache_dir / sha256_hex(request.url.substr(0, request.url.find('#'))).substr(0, 24);
  const std::filesystem::path final_path = dir / safe_file_name(target.path);
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec)
    return {ErrorCode::Io, "cannot create cache directory " + dir.string() + ": " + ec.message()};

  if (request.sha256 && std::filesystem::is_regular_file(final_path, ec)) {
    std::string hex;
    std::uint64_t bytes = 0;
    if (file_sha256(final_path, hex, bytes).ok() && hex == *request.sha256 &&
        (!request.size || *request.size == bytes)) {
      result = {final_path, bytes, hex, true, 0};
      return {};
    }
  }

  const std::filesystem::path tmp = temp_path_beside(final_path, "part");
  Sink sink;
  sink.file = std::fopen(tmp.c_str(), "w+b");
  if (sink.file == nullptr) return {ErrorCode::Io, "cannot create " + tmp.string()};
  sink.cap = policy.max_bytes;
  auto discard = [&] {
    if (sink.file != nullptr) std::fclose(sink.file);
    sink.file = nullptr;
    std::filesystem::remove(tmp, ec);
  };

  Failure failure;
  int redirects = 0;
  bool done = false;
  long delay = policy.retry_delay_ms;
  for (int attempt = 1; attempt <= std::max(1, policy.attempts) && !done;) {
    sink.reset();
    result.attempts++;
    const Attempt a = transfer_once(target.url, target.headers, policy, target.protocols, sink);
    if (a.outcome == Outcome::Done) {
      done = true;
    } else if (a.outcome == Outcome::Redirect) {
      if (target.s3) {
        failure = {ErrorCode::FetchRefused,
                   where + ": S3 answered with a redirect (wrong region or endpoint?)"};
        break;
      }
      if (++redirects > policy.max_redirects) {
        failure = {ErrorCode::FetchRefused,
                   where + ": more than " + std::to_string(policy.max_redirects) + " redirects"};
        break;
      }
      if (Failure f = transport::redirect_target(where, a.location, policy, target); !f.ok()) {
        failure = f;
        break;
      }
    } else if (a.outcome == Outcome::Transient && attempt < policy.attempts) {
      failure = a.failure;
      ++attempt;
      std::this_thread::sleep_for(std::chrono::milliseconds(delay));
      delay *= 2;
    } else {
      failure = a.failure;
      if (a.outcome == Outcome::Transient) {
        failure.message += " (after " + std::to_string(result.attempts) + " attempts)";
      }
      break;
    }
  }
  if (!done) {
    discard();
    result = {};
    // Name the input as given when the failing request went elsewhere (S3 endpoint, redirect).
    if (failure.message.rfind(where, 0) != 0) failure.message = where + ": " + failure.message;
    return failure;
  }

  const std::string hex = sink.sha.hex();
  if (request.size && *request.size != sink.bytes) {
    discard();
    return {ErrorCode::FetchRefused, where + ": got " + std::to_string(sink.bytes) +
                                         " bytes, expected " + std::to_string(*request.size)};
  }
  if (request.sha256 && *request.sha256 != hex) {
    discard();
    return {ErrorCode::FetchRefused,
            where + ": SHA-256 " + hex + " does not match the expected " + *request.sha256};
  }
  const bool closed = std::fclose(sink.file) == 0;
  sink.file = nullptr;
  if (!closed) {
    discard();
    return {ErrorCode::Io, "cannot write " + tmp.string()};
  }
  if (Failure f = commit_temp_file(tmp, final_path); !f.ok()) {
    f.message = where + ": " + f.message;
    return f;
  }
  const int attempts = result.attempts;
  result = {final_path, sink.bytes, hex, false, attempts};
  return {};
}

namespace {

// ---- signed S3 requests: PUT, HEAD, GET into memory ---------------------------------------

struct S3Exchange {
  std::string method;               ///< "PUT", "HEAD" or "GET"
  std::string_view upload;          ///< the PUT body
  std::string* download = nullptr;  ///< where a GET body goes (capped by policy.max_bytes)
};

struct S3Reply {
  long status = 0;
  std::int64_t content_length = -1;  ///< as announced by the server; -1 when unknown
};

// One signed request (signed afresh, so a retry carries a current date). 2xx is Done, and
// so is 404 for HEAD and GET (the caller reads a missing object from the status); transport
// failures and 5xx/429/408 are Transient; other statuses Permanent refusals.
Attempt s3_exchange_once(const UrlParts& parts, const std::string& url, const S3Exchange& exchange,
                         const Policy& policy, S3Reply& reply) {
  Attempt attempt;
  const std::string where = redacted(url);
  const std::string payload_sha256 = sha256_hex(exchange.upload);
  S3Target target;
  if (Failure f = s3_target(parts, url, policy, exchange.method, payload_sha256, target); !f.ok()) {
    attempt.failure = f;
    return attempt;
  }
  if (exchange.method == "PUT") {
    target.headers.push_back("Content-Type: application/octet-stream");
    target.headers.push_back("Expect:");  // no 100-continue round trip
  }
  std::unique_ptr<CURL, CurlDeleter> curl(curl_easy_init());
  std::unique_ptr<curl_slist, SlistDeleter> list;
  for (const std::string& h : target.headers) {
    curl_slist* grown = curl_slist_append(list.get(), h.c_str());
    if (grown == nullptr || !curl) {
      attempt.failure = {ErrorCode::Internal, "libcurl could not build the request"};
      return attempt;
    }
    static_cast<void>(list.release());  // owned by the list curl_slist_append returned
    list.reset(grown);
  }
  struct Body {
    std::string_view upload;
    std::size_t offset = 0;
    std::string* download = nullptr;
    std::uint64_t cap = 0;
    bool over_cap = false;
  } body{exchange.upload, 0, exchange.download, policy.max_bytes, false};
  if (body.download != nullptr) body.download->clear();
  auto on_read = +[](char* buffer, std::size_t size, std::size_t count, void* user) -> std::size_t {
    auto* b = static_cast<Body*>(user);
    const std::size_t n = std::min(size * count, b->upload.size() - b->offset);
    std::copy_n(b->upload.data() + b->offset, n, buffer);
    b->offset += n;
    return n;
  };
  auto on_receive =
      +[](char* data, std::size_t size, std::size_t count, void* user) -> std::size_t {
    auto* b = static_cast<Body*>(user);
    const std::size_t n = size * count;
    if (b->download == nullptr) return n;  // error documents and PUT answers are not kept
    if (b->download->size() + n > b->cap) {
      b->over_cap = true;
      return 0;  // aborts the transfer
    }
    b->download->append(data, n);
    return n;
  };
  Sink sink;  // only for the address policy
  char error_text[CURL_ERROR_SIZE] = "";
  CURL* c = curl.get();
  set_common_options(c, policy, sink.refused_address, error_text);
  curl_easy_setopt(c, CURLOPT_URL, target.url.c_str());
  curl_easy_setopt(c, CURLOPT_PROTOCOLS_STR, "http,https");
  curl_easy_setopt(c, CURLOPT_LOW_SPEED_LIMIT, policy.low_speed_bytes_per_second);
  curl_easy_setopt(c, CURLOPT_LOW_SPEED_TIME, policy.low_speed_seconds);
  if (exchange.method == "PUT") {
    curl_easy_setopt(c, CURLOPT_UPLOAD, 1L);
    curl_easy_setopt(c, CURLOPT_READFUNCTION, on_read);
    curl_easy_setopt(c, CURLOPT_READDATA, &body);
    curl_easy_setopt(c, CURLOPT_INFILESIZE_LARGE, static_cast<curl_off_t>(exchange.upload.size()));
  } else if (exchange.method == "HEAD") {
    curl_easy_setopt(c, CURLOPT_NOBODY, 1L);
  }
  curl_easy_setopt(c, CURLOPT_WRITEFUNCTION, on_receive);
  curl_easy_setopt(c, CURLOPT_WRITEDATA, &body);
  curl_easy_setopt(c, CURLOPT_HTTPHEADER, list.get());
  const CURLcode code = curl_easy_perform(c);
  if (!sink.refused_address.empty()) {
    attempt.failure = {ErrorCode::FetchRefused,
                       where + ": connection to " + sink.refused_address + " refused"};
    return attempt;
  }
  if (body.over_cap) {
    attempt.failure = {ErrorCode::FetchRefused, where + ": larger than the size cap of " +
                                                    std::to_string(policy.max_bytes) + " bytes"};
    return attempt;
  }
  if (code != CURLE_OK) {
    attempt.outcome = transient_curl(code) ? Outcome::Transient : Outcome::Permanent;
    attempt.failure = {ErrorCode::Network,
                       where + ": " + exchange.method + " failed: " +
                           (error_text[0] != '\0' ? error_text : curl_easy_strerror(code))};
    return attempt;
  }
  curl_easy_getinfo(c, CURLINFO_RESPONSE_CODE, &reply.status);
  curl_off_t length = -1;
  curl_easy_getinfo(c, CURLINFO_CONTENT_LENGTH_DOWNLOAD_T, &length);
  reply.content_length = static_cast<std::int64_t>(length);
  const long status = reply.status;
  if ((status >= 200 && status < 300) || (status == 404 && exchange.method != "PUT")) {
    attempt.outcome = Outcome::Done;
    return attempt;
  }
  const bool transient = status >= 500 || status == 429 || status == 408;
  attempt.outcome = transient ? Outcome::Transient : Outcome::Permanent;
  std::string text = where + ": " + exchange.method + " answered HTTP " + std::to_string(status);
  if (status == 403) text += " (access denied: check the S3 credentials and the bucket's policy)";
  if (status >= 300 && status < 400) text += " (a redirect: wrong region or endpoint?)";
  attempt.failure = {transient ? ErrorCode::Network : ErrorCode::FetchRefused, text};
  return attempt;
}

// Runs one signed S3 request with fetch's retry rule: transient outcomes are tried again up to
// policy.attempts times with a doubling delay; the last failure names how many attempts ran.
Failure s3_exchange(const std::string& url, const S3Exchange& exchange, const Policy& policy,
                    S3Reply& reply) {
  global_init();
  const std::string where = redacted(url);
  UrlParts parts;
  if (has_control(url) || !split_url(url, parts) || parts.scheme != "s3") {
    return {ErrorCode::InputInvalid, where + ": not an s3:// URL"};
  }
  if (std::find(policy.schemes.begin(), policy.schemes.end(), "s3") == policy.schemes.end()) {
    return {ErrorCode::FetchRefused, where + ": scheme 's3' is not allowed by the policy"};
  }
  const int attempts = std::max(1, policy.attempts);
  long delay = policy.retry_delay_ms;
  for (int attempt = 1;; ++attempt) {
    reply = {};
    Attempt a = s3_exchange_once(parts, url, exchange, policy, reply);
    if (a.outcome == Outcome::Done) return {};
    if (a.outcome != Outcome::Transient) return a.failure;
    if (attempt >= attempts) {
      a.failure.message += " (after " + std::to_string(attempt) + " attempts)";
      return a.failure;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(delay));
    delay *= 2;
  }
}

}  // namespace

Failure s3_put(const std::string& url, std::string_view bytes, const Policy& policy) {
  S3Reply reply;
  return s3_exchange(url, {"PUT", bytes, nullptr}, policy, reply);
}

Failure s3_head(const std::string& url, const Policy& policy, S3Object& object) {
  object = {};
  S3Reply reply;
  if (Failure f = s3_exchange(url, {"HEAD", {}, nullptr}, policy, reply); !f.ok()) return f;
  object.exists = reply.status != 404;
  if (object.exists && reply.content_length < 0) {
    return {ErrorCode::Network, redacted(url) + ": HEAD answered without a Content-Length"};
  }
  object.size = object.exists ? static_cast<std::uint64_t>(reply.content_length) : 0;
  return {};
}

Failure s3_get(const std::string& url, const Policy& policy, S3Object& object, std::string& bytes) {
  object = {};
  bytes.clear();
  S3Reply reply;
  if (Failure f = s3_exchange(url, {"GET", {}, &bytes}, policy, reply); !f.ok()) {
    bytes.clear();
    return f;
  }
  object.exists = reply.status != 404;
  if (!object.exists) bytes.clear();  // the 404's error document is not the object
  object.size = bytes.size();
  return {};
}

}  // namespace csgtile::worker::fetch
