// Digests and atomic replacement (csgtile/worker/files.h): known vectors, the incremental
// digest against the one-shot one, and commits that refuse or fail leave no temporary.

#include "csgtile/worker/files.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

namespace csgtile::worker {
namespace {

namespace fs = std::filesystem;

fs::path fresh_dir(const std::string& name) {
  fs::path dir =
      fs::temp_directory_path() / ("csgtile-files-" + name + "-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

int entries_in(const fs::path& dir) {
  int n = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++n;
  return n;
}

TEST(Files, IncrementalSha256EqualsOneShotAndStartsAgainOnReset) {
  std::string text;
  for (int i = 0; i < 5000; ++i) text += std::to_string(i * 7919) + ",";
  Sha256 sha;
  for (std::size_t at = 0; at < text.size(); at += 997) sha.update(text.substr(at, 997));
  EXPECT_EQ(sha.hex(), sha256_hex(text));
  sha.reset();
  sha.update("abc");
  EXPECT_EQ(sha.hex(), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
}

TEST(Files, FileDigestCountsBytesAndNamesAnUnreadableFile) {
  const fs::path dir = fresh_dir("digest");
  const std::string text(200000, 'x');
  std::ofstream(dir / "f.bin", std::ios::binary) << text;
  std::string hex;
  std::uint64_t bytes = 0;
  ASSERT_TRUE(file_sha256(dir / "f.bin", hex, bytes).ok());
  EXPECT_EQ(hex, sha256_hex(text));
  EXPECT_EQ(bytes, text.size());
  const Failure missing = file_sha256(dir / "missing.bin", hex, bytes);
  EXPECT_EQ(missing.code, ErrorCode::Io);
  EXPECT_NE(missing.message.find("missing.bin"), std::string::npos) << missing.message;
  fs::remove_all(dir);
}

TEST(Files, HmacAndHexMatchRfc4231) {
  // RFC 4231, test case 2: key "Jefe".
  const auto mac = hmac_sha256("Jefe", "what do ya want for nothing?");
  ASSERT_TRUE(mac.has_value());
  EXPECT_EQ(hex_encode(*mac), "5bdcc146bf60754e6a042426089575c75a003f089d2739839dec58b964ec3843");
  EXPECT_EQ(hex_encode(std::string("\x00\x0f\xf0\xff", 4)), "000ff0ff");
}

TEST(Files, CommitReplacesTheTargetAndLeavesNoTemporary) {
  const fs::path dir = fresh_dir("commit");
  const fs::path target = dir / "out.txt";
  ASSERT_TRUE(write_file_atomic(target, "old").ok());
  const fs::path temp = temp_path_beside(target, "part");
  EXPECT_EQ(temp.parent_path(), dir);
  EXPECT_NE(temp, temp_path_beside(target, "part")) << "two writers never share a temporary";
  std::ofstream(temp, std::ios::binary) << "new";
  ASSERT_TRUE(commit_temp_file(temp, target).ok());
  std::ifstream in(target);
  const std::string got((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(got, "new");
  EXPECT_EQ(entries_in(dir), 1);
  fs::remove_all(dir);
}

TEST(Files, ACommitOntoADirectoryOrAPipeIsRefusedAndTheTemporaryRemoved) {
  const fs::path dir = fresh_dir("refuse");
  fs::create_directories(dir / "taken");
  ASSERT_EQ(::mkfifo((dir / "pipe").c_str(), 0600), 0);
  for (const char* name : {"taken", "pipe"}) {
    const fs::path temp = temp_path_beside(dir / name, "tmp");
    std::ofstream(temp, std::ios::binary) << "bytes";
    const Failure f = commit_temp_file(temp, dir / name);
    EXPECT_EQ(f.code, ErrorCode::Io) << name;
    EXPECT_NE(f.message.find("not a regular file"), std::string::npos) << f.message;
    EXPECT_FALSE(fs::exists(temp)) << name;
    const Failure direct = write_file_atomic(dir / name, "bytes");
    EXPECT_EQ(direct.code, ErrorCode::Io) << name;
  }
  EXPECT_TRUE(fs::is_directory(dir / "taken"));
  EXPECT_TRUE(fs::is_fifo(dir / "pipe"));
  EXPECT_EQ(entries_in(dir), 2);
  // A temporary that is gone (removed by someone else) is an error naming it.
  const Failure gone = commit_temp_file(dir / ".gone.tmp", dir / "out.txt");
  EXPECT_EQ(gone.code, ErrorCode::Io);
  EXPECT_NE(gone.message.find(".gone.tmp"), std::string::npos) << gone.message;
  fs::remove_all(dir);
}

TEST(Files, ABatchWritesEveryFileOrRefusesBeforeRenamingAny) {
  const fs::path dir = fresh_dir("batch");
  const std::vector<std::pair<fs::path, std::string>> files = {
      {dir / "a.txt", "first"}, {dir / "sub" / "b.txt", "second"}, {dir / "c.txt", ""}};
  ASSERT_TRUE(write_files_atomic(files).ok());
  for (const auto& [path, bytes] : files) {
    std::ifstream in(path);
    const std::string got((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_EQ(got, bytes) << path;
  }
  EXPECT_EQ(entries_in(dir), 3);  // a.txt, c.txt, sub: no temporary left
  EXPECT_EQ(entries_in(dir / "sub"), 1);
  // A path taken by a directory is refused before anything is renamed: no file of the batch
  // appears and no temporary stays.
  fs::create_directories(dir / "taken");
  const Failure f = write_files_atomic({{dir / "new.txt", "x"}, {dir / "taken", "y"}});
  EXPECT_EQ(f.code, ErrorCode::Io);
  EXPECT_NE(f.message.find("taken"), std::string::npos) << f.message;
  EXPECT_FALSE(fs::exists(dir / "new.txt"));
  EXPECT_EQ(entries_in(dir), 4);
  EXPECT_TRUE(write_files_atomic({}).ok());
  fs::remove_all(dir);
}

// Temporaries are written and flushed some dozens at a time: a batch of many files is complete,
// and a refusal in a later group (files of earlier groups already flushed, some of its own
// open) still leaves no file of the batch and no temporary.
TEST(Files, AManyFileBatchIsWholeOrNothingAcrossItsFlushGroups) {
  const fs::path dir = fresh_dir("many");
  std::vector<std::pair<fs::path, std::string>> files;
  for (int i = 0; i < 150; ++i) {
    files.push_back(
        {dir / ("f" + std::to_string(i)), std::string(static_cast<std::size_t>(i), 'a' + i % 26)});
  }
  ASSERT_TRUE(write_files_atomic(files).ok());
  for (const auto& [path, bytes] : files) {
    std::string got;
    ASSERT_TRUE(read_file_bytes(path, got).ok()) << path;
    EXPECT_EQ(got, bytes) << path;
  }
  EXPECT_EQ(entries_in(dir), 150);
  fs::remove_all(dir);
  fs::create_directories(dir / "taken");
  for (auto& [path, bytes] : files) path = dir / ("g" + path.filename().string());
  files[130].first = dir / "taken";
  const Failure f = write_files_atomic(files);
  EXPECT_EQ(f.code, ErrorCode::Io);
  EXPECT_NE(f.message.find("taken"), std::string::npos) << f.message;
  EXPECT_EQ(entries_in(dir), 1);  // only "taken"
  fs::remove_all(dir);
}

TEST(Files, ReadFileBytesReadsAllAndNamesAMissingFile) {
  const fs::path dir = fresh_dir("read");
  std::string text(300000, '\0');
  for (std::size_t i = 0; i < text.size(); ++i) text[i] = static_cast<char>(i * 7 % 251);
  std::ofstream(dir / "f.bin", std::ios::binary) << text;
  std::string got = "stale";
  ASSERT_TRUE(read_file_bytes(dir / "f.bin", got).ok());
  EXPECT_EQ(got, text);
  const Failure missing = read_file_bytes(dir / "missing.bin", got);
  EXPECT_EQ(missing.code, ErrorCode::Io);
  EXPECT_NE(missing.message.find("missing.bin"), std::string::npos) << missing.message;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace csgtile::worker
