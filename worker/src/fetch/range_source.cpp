// Random access to an HTTP(S) or S3 object by range requests (see fetch.h).

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstring>
#include <memory>
#include <thread>

#include "fetch/fetch.h"
#include "fetch/transport.h"

namespace csgtile::worker::fetch {

namespace {

constexpr std::size_t kBlocksKept = 8;

struct CurlDeleter {
  void operator()(CURL* c) const { curl_easy_cleanup(c); }
};
struct SlistDeleter {
  void operator()(curl_slist* l) const { curl_slist_free_all(l); }
};

struct Reply {
  long status = 0;
  std::string body;
  std::string content_range;  // the Content-Range header's value
  std::string location;       // a redirect's target
};

struct Receive {
  std::string* body = nullptr;
  std::uint64_t cap = 0;
  bool over_cap = false;
};

std::size_t on_body(char* data, std::size_t size, std::size_t count, void* user) {
  auto* r = static_cast<Receive*>(user);
  const std::size_t n = size * count;
  if (r->body->size() + n > r->cap) {
    r->over_cap = true;
    return 0;
  }
  r->body->append(data, n);
  return n;
}

std::size_t on_header(char* data, std::size_t size, std::size_t count, void* user) {
  const std::size_t n = size * count;
  std::string line(data, n);
  constexpr const char kName[] = "content-range:";
  if (line.size() > sizeof kName - 1) {
    std::string head = line.substr(0, sizeof kName - 1);
    std::transform(head.begin(), head.end(), head.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (head == kName) {
      std::string value = line.substr(sizeof kName - 1);
      while (!value.empty() && (value.back() == '\r' || value.back() == '\n')) value.pop_back();
      while (!value.empty() && value.front() == ' ') value.erase(value.begin());
      *static_cast<std::string*>(user) = value;
    }
  }
  return n;
}

// "bytes a-b/total" or "bytes */total": the total, or -1.
std::int64_t total_of(const std::string& content_range) {
  const auto slash = content_range.rfind('/');
  if (slash == std::string::npos || content_range.rfind("bytes ", 0) != 0) return -1;
  const std::string total = content_range.substr(slash + 1);
  if (total.empty() || total.size() > 18 ||
      !std::all_of(total.begin(), total.end(), [](unsigned char c) { return std::isdigit(c); })) {
    return -1;
  }
  return std::stoll(total);
}

class HttpRangeSource final : public geo::ByteSource {
 public:
  HttpRangeSource(std::string url, Policy policy, std::shared_ptr<RangeStats> stats,
                  std::uint64_t block)
      : geo::ByteSource(transport::redact(url)),
        url_(std::move(url)),
        policy_(std::move(policy)),
        stats_(std::move(stats)),
        block_(std::max<std::uint64_t>(block, 512)) {}

  // The first request: the first block, and the object's size from Content-Range.
  Failure open() {
    Reply reply;
    const std::uint64_t first = std::min<std::uint64_t>(block_, kFirstBlock);
    if (Failure f = get(0, first, reply); !f.ok()) return f;
    if (reply.status == 200) {  // no range support: the whole object came
      whole_ = std::make_unique<std::string>(std::move(reply.body));
      size_ = whole_->size();
      return {};
    }
    if (reply.status == 416) {  // an empty object
      const std::int64_t total = total_of(reply.content_range);
      if (total != 0) return {ErrorCode::Network, name() + ": HTTP 416 for the first bytes"};
      size_ = 0;
      return {};
    }
    const std::int64_t total = total_of(reply.content_range);
    if (total < 0) {
      return {ErrorCode::Network, name() + ": the range answer has no usable Content-Range ('" +
                                      reply.content_range + "')"};
    }
    size_ = static_cast<std::uint64_t>(total);
    if (reply.body.size() != std::min<std::uint64_t>(first, size_)) {
      return {ErrorCode::Network, name() + ": asked for the first " +
                                      std::to_string(std::min<std::uint64_t>(first, size_)) +
                                      " bytes, got " + std::to_string(reply.body.size())};
    }
    // Blocks of a small object stay small (at most 1/16 of it), so that reading a part of
    // it never means fetching all of it.
    block_ = std::max<std::uint64_t>(512, std::min(block_, size_ / 16));
    first_ = std::move(reply.body);
    return {};
  }

  std::uint64_t size() const override { return size_; }

  kernel::Status read_at(std::uint64_t offset, std::span<std::uint8_t> out) override {
    if (out.empty()) return kernel::Status();
    if (offset > size_ || out.size() > size_ - offset) {
      return kernel::Status(kernel::ErrorCode::CorruptData,
                            name() + ": read of " + std::to_string(out.size()) + " bytes at " +
                                std::to_string(offset) + " passes the end (" +
                                std::to_string(size_) + " bytes)");
    }
    if (whole_) {
      std::memcpy(out.data(), whole_->data() + offset, out.size());
      return kernel::Status();
    }
    // The part within the first request's bytes (header, VLRs) comes from them.
    std::size_t done = 0;
    if (offset < first_.size()) {
      done = static_cast<std::size_t>(std::min<std::uint64_t>(out.size(), first_.size() - offset));
      std::memcpy(out.data(), first_.data() + offset, done);
      if (done == out.size()) return kernel::Status();
    }
    if (out.size() - done >= block_) return fetch_exact(offset + done, out.subspan(done));
    // Small reads (headers, VLRs, records): whole aligned blocks, a few kept.
    while (done < out.size()) {
      const std::uint64_t at = offset + done;
      const std::uint64_t start = at / block_ * block_;
      const std::string* block = find(start);
      if (block == nullptr) {
        Reply reply;
        const std::uint64_t n = std::min(block_, size_ - start);
        if (Failure f = get(start, n, reply); !f.ok()) return as_status(f);
        if (Failure f = check(reply, start, n); !f.ok()) return as_status(f);
        block = &keep(start, std::move(reply.body));
      }
      const std::size_t take = static_cast<std::size_t>(
          std::min<std::uint64_t>(out.size() - done, start + block->size() - at));
      std::memcpy(out.data() + done, block->data() + (at - start), take);
      done += take;
    }
    return kernel::Status();
  }

 private:
  kernel::Status as_status(const Failure& f) const {
    // Transport failures are I/O for the reader; the message keeps the cause, the stats the
    // failure itself (its code: Network is retryable).
    if (stats_) stats_->last_failure = f;
    return kernel::Status(kernel::ErrorCode::IoError, f.message);
  }

  kernel::Status fetch_exact(std::uint64_t offset, std::span<std::uint8_t> out) {
    Reply reply;
    if (Failure f = get(offset, out.size(), reply); !f.ok()) return as_status(f);
    if (Failure f = check(reply, offset, out.size()); !f.ok()) return as_status(f);
    std::memcpy(out.data(), reply.body.data(), out.size());
    return kernel::Status();
  }

  Failure check(const Reply& reply, std::uint64_t offset, std::uint64_t n) const {
    if (reply.status != 206 || reply.body.size() != n) {
      return {ErrorCode::Network, name() + ": range " + std::to_string(offset) + "-" +
                                      std::to_string(offset + n - 1) + " answered HTTP " +
                                      std::to_string(reply.status) + " with " +
                                      std::to_string(reply.body.size()) + " bytes"};
    }
    return {};
  }

  const std::string* find(std::uint64_t start) {
    for (auto& [at, bytes] : blocks_) {
      if (at == start) return &bytes;
    }
    return nullptr;
  }
  const std::string& keep(std::uint64_t start, std::string bytes) {
    if (blocks_.size() >= kBlocksKept) blocks_.erase(blocks_.begin());
    blocks_.emplace_back(start, std::move(bytes));
    return blocks_.back().second;
  }

  // GET of [offset, offset + n) with retries (transient failures, fresh S3 signatures) and
  // redirects followed one by one under the policy.
  Failure get(std::uint64_t offset, std::uint64_t n, Reply& reply) {
    transport::Target target;
    if (Failure f = transport::resolve(url_, policy_, false, target); !f.ok()) return f;
    long delay = policy_.retry_delay_ms;
    int redirects = 0;
    Failure last;
    for (int attempt = 1; attempt <= std::max(1, policy_.attempts);) {
      if (target.s3 && attempt > 1) {  // a retry of S3 carries a fresh signature
        if (Failure f = transport::resolve(url_, policy_, false, target); !f.ok()) return f;
      }
      bool transient = false;
      last = once(target, offset, n, reply, transient);
      if (last.ok() && !reply.location.empty()) {
        if (target.s3) return {ErrorCode::FetchRefused, name() + ": S3 answered with a redirect"};
        if (++redirects > policy_.max_redirects) {
          return {ErrorCode::FetchRefused,
                  name() + ": more than " + std::to_string(policy_.max_redirects) + " redirects"};
        }
        if (Failure f = transport::redirect_target(name(), reply.location, policy_, target);
            !f.ok()) {
          return f;
        }
        continue;
      }
      if (last.ok()) {
        if (stats_) {
          stats_->requests += 1;
          stats_->bytes += reply.body.size();
        }
        return {};
      }
      if (!transient || attempt >= policy_.attempts) break;
      ++attempt;
      std::this_thread::sleep_for(std::chrono::milliseconds(delay));
      delay *= 2;
    }
    return last;
  }

  Failure once(const transport::Target& target, std::uint64_t offset, std::uint64_t n, Reply& reply,
               bool& transient) {
    reply = Reply{};
    std::unique_ptr<CURL, CurlDeleter> curl(curl_easy_init());
    if (!curl) return {ErrorCode::Internal, "libcurl could not create a handle"};
    std::unique_ptr<curl_slist, SlistDeleter> list;
    std::vector<std::string> headers = target.headers;
    headers.push_back("Range: bytes=" + std::to_string(offset) + "-" +
                      std::to_string(offset + n - 1));
    for (const std::string& h : headers) {
      curl_slist* grown = curl_slist_append(list.get(), h.c_str());
      if (grown == nullptr) return {ErrorCode::Internal, "libcurl could not build the headers"};
      static_cast<void>(list.release());  // owned by the list curl_slist_append returned
      list.reset(grown);
    }
    CURL* c = curl.get();
    char error_text[CURL_ERROR_SIZE] = "";
    std::string refused;
    transport::set_options(c, policy_, refused, error_text);
    Receive receive{&reply.body, std::max<std::uint64_t>(n, policy_.max_bytes)};
    curl_easy_setopt(c, CURLOPT_URL, target.url.c_str());
    curl_easy_setopt(c, CURLOPT_PROTOCOLS_STR, target.protocols.c_str());
    curl_easy_setopt(c, CURLOPT_LOW_SPEED_LIMIT, policy_.low_speed_bytes_per_second);
    curl_easy_setopt(c, CURLOPT_LOW_SPEED_TIME, policy_.low_speed_seconds);
    curl_easy_setopt(c, CURLOPT_HTTPHEADER, list.get());
    curl_easy_setopt(c, CURLOPT_WRITEFUNCTION, on_body);
    curl_easy_setopt(c, CURLOPT_WRITEDATA, &receive);
    curl_easy_setopt(c, CURLOPT_HEADERFUNCTION, on_header);
    curl_easy_setopt(c, CURLOPT_HEADERDATA, &reply.content_range);
    const CURLcode code = curl_easy_perform(c);
    if (!refused.empty()) {
      return {ErrorCode::FetchRefused, name() + ": connection to " + refused + " refused"};
    }
    if (receive.over_cap) {
      return {ErrorCode::FetchRefused, name() + ": answer larger than the size cap of " +
                                           std::to_string(policy_.max_bytes) + " bytes"};
    }
    if (code != CURLE_OK) {
      transient = transport::transient(code);
      return {ErrorCode::Network,
              name() + ": " + (error_text[0] != '\0' ? error_text : curl_easy_strerror(code))};
    }
    curl_easy_getinfo(c, CURLINFO_RESPONSE_CODE, &reply.status);
    if (reply.status == 200 || reply.status == 206 || reply.status == 416) return {};
    if (reply.status == 301 || reply.status == 302 || reply.status == 303 || reply.status == 307 ||
        reply.status == 308) {
      char* location = nullptr;
      curl_easy_getinfo(c, CURLINFO_REDIRECT_URL, &location);
      if (location == nullptr) {
        return {ErrorCode::FetchRefused, name() + ": redirect without a Location"};
      }
      reply.location = location;
      return {};
    }
    transient = reply.status >= 500 || reply.status == 429 || reply.status == 408;
    return {transient ? ErrorCode::Network : ErrorCode::FetchRefused,
            name() + ": HTTP " + std::to_string(reply.status)};
  }

  std::string url_;
  Policy policy_;
  std::shared_ptr<RangeStats> stats_;
  std::uint64_t size_ = 0;
  std::unique_ptr<std::string> whole_;
  std::vector<std::pair<std::uint64_t, std::string>> blocks_;
  std::string first_;  // the first bytes (header, VLRs), from the first request
  static constexpr std::uint64_t kFirstBlock = 16 * 1024;
  std::uint64_t block_;  // small reads are served from aligned blocks this size
};

}  // namespace

Failure open_range_source(const std::string& url, const Policy& policy,
                          std::unique_ptr<geo::ByteSource>& source,
                          std::shared_ptr<RangeStats> stats, std::uint64_t block_bytes) {
  transport::init();
  source.reset();
  auto made = std::make_unique<HttpRangeSource>(url, policy, std::move(stats), block_bytes);
  if (Failure f = made->open(); !f.ok()) return f;
  source = std::move(made);
  return {};
}

bool is_remote_url(const std::string& text) {
  return is_url(text) && text.rfind("file://", 0) != 0;
}

Failure open_las(const std::string& input, const Policy& policy,
                 std::unique_ptr<geo::LasReader>& reader, std::shared_ptr<RangeStats> stats) {
  reader.reset();
  kernel::Result<std::unique_ptr<geo::LasReader>> opened =
      kernel::Error{kernel::ErrorCode::InvalidArgument, "unopened"};
  if (is_remote_url(input)) {
    std::unique_ptr<geo::ByteSource> source;
    if (Failure f = open_range_source(input, policy, source, std::move(stats)); !f.ok()) return f;
    opened = geo::LasReader::open_source(std::move(source));
  } else if (input.rfind("file://", 0) == 0) {
    const std::string path = input.substr(7);
    opened = geo::LasReader::open(path.substr(0, path.find('#')));
  } else {
    opened = geo::LasReader::open(input);
  }
  if (!opened.ok()) return failure_of(opened.error());
  reader = std::move(opened).value();
  return {};
}

}  // namespace csgtile::worker::fetch
