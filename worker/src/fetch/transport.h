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
struct Target {
  std::string url;
  std::vector<std::string> headers;
  std::string protocols;
  bool s3 = false;
};

/// curl_global_init, once.
void init();
/// The URL without credentials, for messages.
std::string redact(const std::string& url);
/// Checks `url` against the policy (scheme allowed, no credentials, no control characters)
/// and builds its GET (S3: path-style on the endpoint, signed now; sign again per request).
/// Only http, https and s3. Errors: InputInvalid, FetchRefused, ConfigInvalid.
Failure resolve(const std::string& url, const Policy& policy, Target& target);
/// The target of a redirect from `from` to `location` (http(s) only, never https → http).
Failure redirect_target(const std::string& from, const std::string& location, const Policy& policy,
                        Target& target);
/// Timeouts, TLS verification, user agent, error buffer and the address policy (a refused
/// address is written to `refused_address`).
void set_options(CURL* c, const Policy& policy, std::string& refused_address, char* error_text);
/// Transport errors worth another attempt.
bool transient(CURLcode code);

}  // namespace csgtile::worker::fetch::transport
