#pragma once
// What fetch.cpp shares with the range reader (range_source.cpp): URL policy checks and S3
// signing for a GET, the libcurl options every transfer carries (timeouts, TLS, the address
// policy), redaction and which transport errors are transient. Private to worker/fetch.

#include <curl/curl.h>

#include <string>
#include <vector>

#include "fetch/fetch.h"

namespace csgtile::worker::fetch::transport {

/// A GET ready to send: the URL to ask, its headers (S3: signed), the protocols allowed.
/// Shared by fetch() and the range reader: one set of URL rules for both.
struct Target {
  std::string url;
  std::vector<std::string> headers;
  std::string protocols;
  std::string path;  ///< the path of the URL as written (the cache names files by it)
  bool s3 = false;
};

/// curl_global_init, once.
void init();
/// The URL without credentials, for messages.
std::string redact(const std::string& url);
/// Checks `url` against the policy (scheme allowed, no credentials, no control characters)
/// and builds its GET (S3: path-style on the endpoint, signed now; sign again per request).
/// http, https and s3, and file when `allow_file`. Errors: InputInvalid, FetchRefused,
/// ConfigInvalid.
Failure resolve(const std::string& url, const Policy& policy, bool allow_file, Target& target);
/// Moves `target` to a redirect's `location` (an allowed http(s) URL without credentials,
/// never from https to http); errors name the input as `where`.
Failure redirect_target(const std::string& where, const std::string& location, const Policy& policy,
                        Target& target);
/// Timeouts, TLS verification, user agent, error buffer and the address policy (a refused
/// address is written to `refused_address`).
void set_options(CURL* c, const Policy& policy, std::string& refused_address, char* error_text);
/// Transport errors worth another attempt.
bool transient(CURLcode code);

}  // namespace csgtile::worker::fetch::transport
