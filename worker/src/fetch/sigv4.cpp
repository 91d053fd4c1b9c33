#include "fetch/sigv4.h"

#include <algorithm>
#include <cctype>
#include <ctime>
#include <optional>

#include "csgtile/worker/files.h"

namespace csgtile::worker::fetch {
namespace {

std::string lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return text;
}

std::string trim(const std::string& text) {
  std::size_t begin = text.find_first_not_of(" \t");
  if (begin == std::string::npos) return {};
  std::size_t end = text.find_last_not_of(" \t");
  return text.substr(begin, end - begin + 1);
}

}  // namespace

std::string uri_encode(const std::string& text, bool keep_slash) {
  static const char digits[] = "0123456789ABCDEF";
  std::string out;
  out.reserve(text.size());
  for (unsigned char c : text) {
    if (std::isalnum(c) || c == '-' || c == '_' || c == '.' || c == '~' ||
        (keep_slash && c == '/')) {
      out.push_back(static_cast<char>(c));
    } else {
      out.push_back('%');
      out.push_back(digits[c >> 4]);
      out.push_back(digits[c & 15]);
    }
  }
  return out;
}

std::string amz_date_now() {
  std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y%m%dT%H%M%SZ", &utc);
  return text;
}

worker::Result<SigV4Result> sign_v4(const SigV4Request& request, const std::string& access_key,
                                    const std::string& secret_key) {
  // Canonical headers: lower-case names, trimmed values, sorted by name.
  std::vector<std::pair<std::string, std::string>> headers = {
      {"host", trim(request.host)},
      {"x-amz-content-sha256", request.payload_sha256},
      {"x-amz-date", request.amz_date}};
  for (const auto& [name, value] : request.extra_headers)
    headers.emplace_back(lower(name), trim(value));
  std::sort(headers.begin(), headers.end());

  std::string canonical_headers;
  std::string signed_headers;
  for (const auto& [name, value] : headers) {
    canonical_headers += name + ":" + value + "\n";
    if (!signed_headers.empty()) signed_headers += ";";
    signed_headers += name;
  }

  SigV4Result result;
  result.canonical_request = request.method + "\n" + request.canonical_path + "\n" +
                             request.canonical_query + "\n" + canonical_headers + "\n" +
                             signed_headers + "\n" + request.payload_sha256;
  const std::string day = request.amz_date.substr(0, 8);
  const std::string scope = day + "/" + request.region + "/" + request.service + "/aws4_request";
  result.string_to_sign = "AWS4-HMAC-SHA256\n" + request.amz_date + "\n" + scope + "\n" +
                          sha256_hex(result.canonical_request);

  // The signing key: the secret chained through the scope's parts, then the string to sign.
  const std::string terminator = "aws4_request";
  std::optional<std::string> mac = "AWS4" + secret_key;
  const std::string* const parts[] = {&day, &request.region, &request.service, &terminator,
                                      &result.string_to_sign};
  for (const std::string* part : parts) {
    mac = hmac_sha256(*mac, *part);
    if (!mac) return Failure{ErrorCode::Internal, "HMAC-SHA256 failed in OpenSSL"};
  }
  result.signature = hex_encode(*mac);
  result.authorization = "AWS4-HMAC-SHA256 Credential=" + access_key + "/" + scope +
                         ", SignedHeaders=" + signed_headers + ", Signature=" + result.signature;

  for (const auto& [name, value] : headers) {
    if (name != "host") result.headers.push_back(name + ": " + value);
  }
  result.headers.push_back("Authorization: " + result.authorization);
  return result;
}

}  // namespace csgtile::worker::fetch
