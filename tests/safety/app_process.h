// What the process-level safety tests share: running an app as a user does (its output and
// errors in files), waiting for it with a timeout, the folder it leaves, a small disk.
#pragma once

#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace app_test {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

inline fs::path freshDir(const std::string& name) {
  const fs::path d = fs::current_path() / "app_safety" / name;
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

inline std::string readText(const fs::path& p) {
  std::ifstream in(p);
  std::ostringstream os;
  os << in.rdbuf();
  return os.str();
}

inline std::set<std::string> listing(const fs::path& dir) {
  std::set<std::string> out;
  if (!fs::exists(dir)) return out;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    out.insert(fs::relative(e.path(), dir).string());
  return out;
}

inline std::size_t lineCount(const std::string& s) {
  std::size_t n = 0;
  for (const char c : s) n += c == '\n';
  return n;
}

#define EXPECT_CONTAINS(haystack, needle) \
  EXPECT_NE(std::string(haystack).find(needle), std::string::npos) << (haystack)

/// A process of one of the apps, its output in files of `dir`.
class Process {
 public:
  Process(const std::vector<std::string>& argv, const fs::path& dir, const std::string& tag)
      : out_(dir / (tag + ".out")), err_(dir / (tag + ".err")) {
    pid_ = fork();
    if (pid_ == 0) {
      const int o = open(out_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      const int e = open(err_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      const int in = open("/dev/null", O_RDONLY);
      dup2(o, 1);
      dup2(e, 2);
      dup2(in, 0);
      std::vector<char*> args;
      for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
      args.push_back(nullptr);
      execv(args[0], args.data());
      _exit(127);
    }
  }
  ~Process() {
    if (pid_ > 0 && status_ < 0) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
  }
  pid_t pid() const { return pid_; }
  void signal(int sig) const { kill(pid_, sig); }
  /// Waits for the end (at most `timeout_s`) and returns the wait status.
  int wait(double timeout_s = 120) {
    const auto t0 = Clock::now();
    while (status_ < 0) {
      int st = 0;
      if (waitpid(pid_, &st, WNOHANG) == pid_) {
        status_ = st;
        break;
      }
      if (std::chrono::duration<double>(Clock::now() - t0).count() > timeout_s) {
        kill(pid_, SIGKILL);
        waitpid(pid_, &st, 0);
        status_ = st;
        ADD_FAILURE() << "process did not end within " << timeout_s << " s";
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    return status_;
  }
  bool running() {
    int st = 0;
    if (status_ >= 0) return false;
    if (waitpid(pid_, &st, WNOHANG) == pid_) {
      status_ = st;
      return false;
    }
    return true;
  }
  std::string out() const { return readText(out_); }
  std::string err() const { return readText(err_); }

 private:
  fs::path out_, err_;
  pid_t pid_ = -1;
  int status_ = -1;
};

/// Polls until `pred` or the timeout.
template <class Pred>
inline bool waitUntil(Pred pred, double timeout_s = 60) {
  const auto t0 = Clock::now();
  while (!pred()) {
    if (std::chrono::duration<double>(Clock::now() - t0).count() > timeout_s) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return true;
}

/// Starts `argv`, and sends `sig` while the run is working (its staging folder exists), frozen
/// (SIGSTOP) so that it cannot finish in between; false when the run ended before (then retry).
inline bool interruptWhileStaged(Process& p, const fs::path& staging, int sig) {
  if (!waitUntil([&] { return fs::exists(staging) || !p.running(); })) return false;
  p.signal(SIGSTOP);
  const bool staged = fs::exists(staging);
  if (staged) p.signal(sig);
  p.signal(SIGCONT);
  return staged;
}

inline bool killedBy(int status, int sig) { return WIFSIGNALED(status) && WTERMSIG(status) == sig; }
inline int exitCode(int status) { return WIFEXITED(status) ? WEXITSTATUS(status) : -1; }

/// Runs `script` in a private mount namespace with a `size` tmpfs at `mnt`; false when this
/// machine does not allow it (not root, no unshare).
inline bool withSmallDisk(const fs::path& mnt, const std::string& size, const std::string& script,
                          const fs::path& log) {
  fs::create_directories(mnt);
  const std::string cmd = "unshare -m sh -c 'mount -t tmpfs -o size=" + size + " none " +
                          mnt.string() + " 2>/dev/null || exit 77; " + script + "' > " +
                          log.string() + " 2>&1";
  const int st = std::system(cmd.c_str());
  return !(WIFEXITED(st) && WEXITSTATUS(st) == 77);
}

/// freeinit-online on any free port; returns the port once it listens.
inline int listeningPort(Process& online) {
  int port = 0;
  EXPECT_TRUE(waitUntil([&] {
    std::smatch m;
    const std::string out = online.out();
    if (std::regex_search(out, m, std::regex("Listening on UDP 127\\.0\\.0\\.1:([0-9]+)")))
      port = std::stoi(m[1]);
    return port != 0 || !online.running();
  }));
  return port;
}

}  // namespace app_test
