#include "background_process.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>

namespace csgtile::test {

BackgroundProcess::BackgroundProcess(const std::string& command, double timeout_seconds) {
  int fds[2];
  if (pipe2(fds, O_CLOEXEC) != 0) {
    problem_ = "pipe failed";
    return;
  }
  pid_ = fork();
  if (pid_ < 0) {
    problem_ = "fork failed";
    return;
  }
  if (pid_ == 0) {
    setpgid(0, 0);  // its own group: the destructor kills the server and its children
    dup2(fds[1], STDOUT_FILENO);
    execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  setpgid(pid_, pid_);
  close(fds[1]);
  out_ = fds[0];
  const auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::milliseconds(static_cast<long>(timeout_seconds * 1000));
  std::string line;
  while (std::chrono::steady_clock::now() < deadline) {
    pollfd p{out_, POLLIN, 0};
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    if (poll(&p, 1, static_cast<int>(std::max<long>(1, left.count()))) <= 0) continue;
    char c = 0;
    const ssize_t n = read(out_, &c, 1);
    if (n <= 0) {
      int status = 0;
      waitpid(pid_, &status, 0);
      problem_ =
          "exited before printing a line (status " + std::to_string(status) + "): " + command;
      pid_ = -1;
      return;
    }
    if (c == '\n') {
      first_line_ = line;
      return;
    }
    line.push_back(c);
  }
  problem_ = "printed no line within the timeout: " + command;
}

BackgroundProcess::~BackgroundProcess() {
  if (pid_ > 0) {
    kill(-pid_, SIGTERM);
    int status = 0;
    for (int i = 0; i < 50; ++i) {
      if (waitpid(pid_, &status, WNOHANG) == pid_) {
        pid_ = -1;
        break;
      }
      usleep(20000);
    }
    if (pid_ > 0) {
      kill(-pid_, SIGKILL);
      waitpid(pid_, &status, 0);
    }
  }
  if (out_ >= 0) close(out_);
}

}  // namespace csgtile::test
