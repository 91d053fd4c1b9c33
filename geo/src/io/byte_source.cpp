#include "io/byte_source.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <system_error>

namespace csgtile::geo::detail {

namespace {

using kernel::ErrorCode;

class FileSource final : public ByteSource {
 public:
  FileSource(std::string name, int fd, std::uint64_t size)
      : ByteSource(std::move(name)), fd_(fd), size_(size) {}
  ~FileSource() override { ::close(fd_); }
  FileSource(const FileSource&) = delete;
  FileSource& operator=(const FileSource&) = delete;

  std::uint64_t size() const override { return size_; }

  kernel::Status read_at(std::uint64_t offset, std::span<std::uint8_t> out) override {
    if (offset > size_ || out.size() > size_ - offset) {
      return {ErrorCode::CorruptData, name() + ": read of " + std::to_string(out.size()) +
                                          " bytes at offset " + std::to_string(offset) +
                                          " passes the end of the file (" + std::to_string(size_) +
                                          " bytes)"};
    }
    std::size_t done = 0;
    while (done < out.size()) {
      const ssize_t n =
          ::pread(fd_, out.data() + done, out.size() - done, static_cast<off_t>(offset + done));
      if (n < 0) {
        if (errno == EINTR) continue;
        return {ErrorCode::IoError, name() + ": read failed at offset " +
                                        std::to_string(offset + done) + ": " +
                                        std::generic_category().message(errno)};
      }
      // The file shrank under us: a short read is an I/O failure, not corrupt data.
      if (n == 0) {
        return {ErrorCode::IoError, name() + ": file ended at offset " +
                                        std::to_string(offset + done) + " while " +
                                        std::to_string(size_) + " bytes were expected"};
      }
      done += static_cast<std::size_t>(n);
    }
    return {};
  }

 private:
  int fd_;
  std::uint64_t size_;
};

class MemorySource final : public ByteSource {
 public:
  MemorySource(std::string name, std::span<const std::uint8_t> bytes)
      : ByteSource(std::move(name)), bytes_(bytes) {}
  std::uint64_t size() const override { return bytes_.size(); }
  kernel::Status read_at(std::uint64_t offset, std::span<std::uint8_t> out) override {
    if (offset > bytes_.size() || out.size() > bytes_.size() - offset) {
      return {ErrorCode::CorruptData, name() + ": read of " + std::to_string(out.size()) +
                                          " bytes at offset " + std::to_string(offset) +
                                          " passes the end of the data (" +
                                          std::to_string(bytes_.size()) + " bytes)"};
    }
    if (!out.empty()) std::memcpy(out.data(), bytes_.data() + offset, out.size());
    return {};
  }

 private:
  std::span<const std::uint8_t> bytes_;
};

}  // namespace

kernel::Result<std::unique_ptr<ByteSource>> open_file_source(const std::filesystem::path& path) {
  const std::string name = path.string();
  const int fd = ::open(name.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    return kernel::Error{ErrorCode::IoError,
                         name + ": cannot open: " + std::generic_category().message(errno)};
  }
  struct stat st {};
  if (::fstat(fd, &st) != 0) {
    const int err = errno;
    ::close(fd);
    return kernel::Error{ErrorCode::IoError,
                         name + ": cannot stat: " + std::generic_category().message(err)};
  }
  if (!S_ISREG(st.st_mode)) {
    ::close(fd);
    return kernel::Error{ErrorCode::IoError, name + ": not a regular file"};
  }
  return std::unique_ptr<ByteSource>(
      std::make_unique<FileSource>(name, fd, static_cast<std::uint64_t>(st.st_size)));
}

std::unique_ptr<ByteSource> memory_source(std::string name, std::span<const std::uint8_t> bytes) {
  return std::make_unique<MemorySource>(std::move(name), bytes);
}

SequentialReader::SequentialReader(ByteSource& source, std::uint64_t start, std::size_t buffer_size)
    : source_(source),
      // No larger than the data (plus one byte, so that a full buffer always means a line
      // longer than the data could hold): small files do not pay for a 1 MiB buffer.
      buffer_(static_cast<std::size_t>(std::max<std::uint64_t>(
          64, std::min<std::uint64_t>(source.size() - std::min(start, source.size()) + 1,
                                      buffer_size)))),
      file_position_(std::min(start, source.size())),
      position_(std::min(start, source.size())) {}

kernel::Status SequentialReader::fill() {
  // Keep the unread tail, then top the buffer up from the source.
  if (begin_ > 0) {
    std::memmove(buffer_.data(), buffer_.data() + begin_, end_ - begin_);
    end_ -= begin_;
    begin_ = 0;
  }
  const std::uint64_t left = source_.size() - file_position_;
  const std::size_t n =
      static_cast<std::size_t>(std::min<std::uint64_t>(left, buffer_.size() - end_));
  if (n == 0) return {};
  auto status = source_.read_at(file_position_, std::span(buffer_.data() + end_, n));
  if (!status.ok()) return status;
  end_ += n;
  file_position_ += n;
  return {};
}

kernel::Result<bool> SequentialReader::next_line(std::string_view& line) {
  std::size_t scanned = begin_;
  for (;;) {
    const auto* first = buffer_.data() + scanned;
    const auto* newline =
        static_cast<const std::uint8_t*>(std::memchr(first, '\n', end_ - scanned));
    if (newline != nullptr) {
      const std::size_t stop = static_cast<std::size_t>(newline - buffer_.data());
      std::size_t length = stop - begin_;
      if (length > 0 && buffer_[begin_ + length - 1] == '\r') --length;
      line = std::string_view(reinterpret_cast<const char*>(buffer_.data() + begin_), length);
      position_ += stop + 1 - begin_;
      begin_ = stop + 1;
      ++line_number_;
      return true;
    }
    if (file_position_ == source_.size()) {
      if (begin_ == end_) return false;
      // The last line has no newline.
      std::size_t length = end_ - begin_;
      if (buffer_[begin_ + length - 1] == '\r') --length;
      line = std::string_view(reinterpret_cast<const char*>(buffer_.data() + begin_), length);
      position_ += end_ - begin_;
      begin_ = end_;
      ++line_number_;
      return true;
    }
    if (begin_ == 0 && end_ == buffer_.size()) {
      return kernel::Error{kernel::ErrorCode::CorruptData,
                           source_.name() + ": line " + std::to_string(line_number_ + 1) +
                               " is longer than " + std::to_string(buffer_.size()) +
                               " bytes (binary data in a text file?)"};
    }
    scanned = end_ - begin_;
    auto status = fill();
    if (!status.ok()) return status.error();
  }
}

kernel::Status SequentialReader::read_exact(std::span<std::uint8_t> out) {
  std::size_t done = 0;
  // Serve what is buffered, then read the rest straight from the source.
  const std::size_t buffered = std::min(out.size(), end_ - begin_);
  if (buffered > 0) {
    std::memcpy(out.data(), buffer_.data() + begin_, buffered);
    begin_ += buffered;
    done = buffered;
  }
  if (done < out.size()) {
    const std::size_t rest = out.size() - done;
    if (rest > source_.size() - file_position_) {
      return {kernel::ErrorCode::CorruptData,
              source_.name() + ": data ends at byte " + std::to_string(source_.size()) + ", " +
                  std::to_string(rest - (source_.size() - file_position_)) +
                  " bytes short of the record being read"};
    }
    auto status = source_.read_at(file_position_, out.subspan(done));
    if (!status.ok()) return status;
    file_position_ += rest;
  }
  position_ += out.size();
  return {};
}

kernel::Status SequentialReader::skip(std::uint64_t count) {
  if (count > remaining()) {
    return {kernel::ErrorCode::CorruptData,
            source_.name() + ": data ends at byte " + std::to_string(source_.size()) + ", " +
                std::to_string(count - remaining()) + " bytes short of the records being skipped"};
  }
  const std::size_t buffered =
      static_cast<std::size_t>(std::min<std::uint64_t>(count, end_ - begin_));
  begin_ += buffered;
  file_position_ += count - buffered;
  position_ += count;
  return {};
}

}  // namespace csgtile::geo::detail
