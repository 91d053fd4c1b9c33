#pragma once
/// \file
/// AWS Signature Version 4 for S3 requests (internal to the worker's fetch/publish).
///
/// We sign ourselves rather than through libcurl's CURLOPT_AWS_SIGV4: Debian's libcurl 7.88
/// signs the raw path and query and leaves out `x-amz-content-sha256`, which S3 requires.
/// The caller builds the URL from the same canonical (already percent-encoded) path it
/// passes here, so what is signed is exactly what is sent.

#include <string>
#include <utility>
#include <vector>

#include "csgtile/worker/errors.h"

namespace csgtile::worker::fetch {

struct SigV4Request {
  std::string method = "GET";
  std::string host;             ///< as sent in Host: "bucket.s3.amazonaws.com" or "127.0.0.1:4569"
  std::string canonical_path;   ///< percent-encoded once, starting with '/'
  std::string canonical_query;  ///< "a=1&b=2", keys sorted, percent-encoded; empty when none
  std::string payload_sha256;   ///< lower-case hex SHA-256 of the body, or "UNSIGNED-PAYLOAD"
  std::string amz_date;         ///< "YYYYMMDDTHHMMSSZ"
  std::string region;           ///< e.g. "us-east-1"
  std::string service = "s3";
  /// Further headers to sign (name, value), e.g. x-amz-security-token, range.
  std::vector<std::pair<std::string, std::string>> extra_headers;
};

struct SigV4Result {
  std::string canonical_request;
  std::string string_to_sign;
  std::string signature;      ///< lower-case hex
  std::string authorization;  ///< value of the Authorization header
  /// Every header to send (besides Host, which libcurl sets from the URL): x-amz-date,
  /// x-amz-content-sha256, the extra headers and Authorization, as "name: value".
  std::vector<std::string> headers;
};

/// Signs `request`. Error: Internal when OpenSSL's HMAC fails.
worker::Result<SigV4Result> sign_v4(const SigV4Request& request, const std::string& access_key,
                                    const std::string& secret_key);

/// RFC 3986 percent-encoding as S3 wants it: unreserved characters kept, '/' kept when
/// `keep_slash`, everything else %XX (upper-case hex).
std::string uri_encode(const std::string& text, bool keep_slash);

/// "YYYYMMDDTHHMMSSZ" of the current UTC time.
std::string amz_date_now();

}  // namespace csgtile::worker::fetch
