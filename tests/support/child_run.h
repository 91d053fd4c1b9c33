#pragma once
/// \file
/// Runs a benchmark's measurement in a forked child, so that its peak memory is its own and a
/// crash ends only the child: the child computes a trivially copyable result and writes it
/// through a pipe.

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <cstring>
#include <functional>
#include <optional>
#include <type_traits>

namespace csgtile::test {

/// What a child gave back.
template <typename T>
struct ChildRun {
  std::optional<T> result;  ///< absent when the child died or its result did not arrive
  long peak_kb = 0;         ///< the child's peak resident set
  int status = 0;           ///< as waitpid reports it
};

/// Forks, runs `work` in the child and returns its result, with the child's peak RSS.
template <typename T>
ChildRun<T> run_in_child(const std::function<T()>& work) {
  static_assert(std::is_trivially_copyable_v<T>, "the result crosses a pipe as bytes");
  ChildRun<T> out;
  int fd[2];
  if (pipe(fd) != 0) return out;
  std::fflush(stdout);
  const pid_t pid = fork();
  if (pid == 0) {
    close(fd[0]);
    const T value = work();
    const ssize_t w = write(fd[1], &value, sizeof value);
    _exit(w == static_cast<ssize_t>(sizeof value) ? 0 : 1);
  }
  close(fd[1]);
  std::array<char, sizeof(T)> bytes{};
  std::size_t have = 0;
  while (have < bytes.size()) {
    const ssize_t got = read(fd[0], bytes.data() + have, bytes.size() - have);
    if (got <= 0) break;
    have += static_cast<std::size_t>(got);
  }
  close(fd[0]);
  rusage usage{};
  wait4(pid, &out.status, 0, &usage);
  out.peak_kb = usage.ru_maxrss;
  if (have == bytes.size() && WIFEXITED(out.status) && WEXITSTATUS(out.status) == 0) {
    T value;
    std::memcpy(&value, bytes.data(), sizeof value);
    out.result = value;
  }
  return out;
}

}  // namespace csgtile::test
