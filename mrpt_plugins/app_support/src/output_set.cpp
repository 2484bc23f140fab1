#include <fcntl.h>
#include <fnmatch.h>
#include <freeinit/app_support/output_set.h>
#include <freeinit/app_support/stop_signal.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <ostream>
#include <sstream>

namespace freeinit::app_support {
namespace {

namespace fs = std::filesystem;

constexpr const char* kJournal = ".install";
constexpr const char* kReserve = ".reserve";

std::string sysError() { return std::strerror(errno); }

/// "pid 123: freeinit ini/freeinit.ini a.rawlog (since 2025-12-01 21:55:03)".
std::string holderText() {
  std::string cmd;
  std::ifstream f("/proc/self/cmdline", std::ios::binary);
  for (std::string arg; std::getline(f, arg, '\0');) {
    if (cmd.empty()) arg = fs::path(arg).filename().string();
    cmd += (cmd.empty() ? "" : " ") + arg;
  }
  char when[32] = "";
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  localtime_r(&now, &tm);
  std::strftime(when, sizeof(when), "%Y-%m-%d %H:%M:%S", &tm);
  return "pid " + std::to_string(getpid()) + ": " + (cmd.empty() ? "?" : cmd) + ", since " + when;
}

/// A file system with (almost) no room left: a failed write there is the full disk's doing.
bool fileSystemFull(const std::string& path) {
  struct statvfs s {};
  if (statvfs(path.c_str(), &s) != 0) return false;
  const double free_bytes = static_cast<double>(s.f_bavail) * static_cast<double>(s.f_frsize);
  return free_bytes < 1024.0 * 1024.0;
}

void replaceAll(std::string& s, const std::string& from, const std::string& to) {
  if (from.empty()) return;
  for (std::size_t p = s.find(from); p != std::string::npos; p = s.find(from, p + to.size()))
    s.replace(p, from.size(), to);
}

std::string joined(const fs::path& dir, const std::string& name) { return (dir / name).string(); }

/// The last-modification time of `p`, "YYYYmmdd-HHMMSS" (local time).
std::string stampOf(const fs::path& p) {
  struct stat st {};
  std::time_t t = std::time(nullptr);
  if (::stat(p.c_str(), &st) == 0) t = st.st_mtime;
  std::tm tm{};
  localtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof(buf), "%Y%m%d-%H%M%S", &tm);
  return buf;
}

/// "live.rawlog" -> ("live", ".rawlog").
std::pair<std::string, std::string> splitExtension(const std::string& name) {
  const auto dot = name.rfind('.');
  if (dot == std::string::npos || dot == 0) return {name, ""};
  return {name.substr(0, dot), name.substr(dot)};
}

}  // namespace

OutputSet::OutputSet(std::string dir, std::string name, OutputSetOptions options, std::ostream& log)
    : dir_(dir.empty() ? std::string(".") : std::move(dir)),
      name_(std::move(name)),
      options_(std::move(options)),
      log_(log) {
  const std::string prefix = name_.empty() ? "" : "." + name_;
  staging_ = joined(dir_, prefix + (name_.empty() ? ".freeinit.staging" : ".freeinit.staging"));
  lock_path_ = joined(dir_, prefix + ".freeinit.lock");
  std::error_code ec;
  if (fs::exists(dir_, ec) && !fs::is_directory(dir_, ec))
    throw OutputError(dir_ + ": not a folder (the outputs need one)");
  for (fs::path p = dir_; !p.empty() && !fs::exists(p, ec); p = p.parent_path())
    created_dirs_.push_back(p.string());
  fs::create_directories(dir_, ec);
  if (ec) {
    created_dirs_.clear();
    throw OutputError(dir_ + ": cannot create the output folder: " + ec.message());
  }
  try {
    lock();
    recover();
    fs::create_directory(staging_);
    holdReserve();
  } catch (...) {
    if (lock_fd_ >= 0) unlock();
    for (const auto& d : created_dirs_) fs::remove(d, ec);  // only empty ones go
    done_ = true;
    throw;
  }
}

OutputSet::~OutputSet() {
  if (!done_) abandon();
}

void OutputSet::lock() {
  const std::string where = name_.empty() ? dir_ : joined(dir_, name_);
  for (int attempt = 0;; ++attempt) {
    lock_fd_ = ::open(lock_path_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (lock_fd_ < 0)
      throw OutputError(where + ": cannot create the lock file " + lock_path_ + ": " + sysError());
    if (::flock(lock_fd_, LOCK_EX | LOCK_NB) != 0) {
      const int err = errno;
      char buf[512] = {};
      const ssize_t n = ::pread(lock_fd_, buf, sizeof(buf) - 1, 0);
      ::close(lock_fd_);
      lock_fd_ = -1;
      if (err != EWOULDBLOCK)
        throw OutputError(where + ": cannot lock " + lock_path_ + ": " + std::strerror(err));
      std::string holder(buf, n > 0 ? static_cast<std::size_t>(n) : 0);
      while (!holder.empty() && (holder.back() == '\n' || holder.back() == '\0')) holder.pop_back();
      throw OutputBusy(where + ": in use by another run (" +
                       (holder.empty() ? std::string("holder unknown") : holder) +
                       "): wait for it to end or choose another output");
    }
    // The file may have been removed by its previous holder between open() and flock(): then
    // this lock is on a file nobody else will see; take the one at the path.
    struct stat a {
    }, b{};
    if (::fstat(lock_fd_, &a) == 0 && ::stat(lock_path_.c_str(), &b) == 0 && a.st_ino == b.st_ino &&
        a.st_dev == b.st_dev)
      break;
    ::close(lock_fd_);
    lock_fd_ = -1;
    if (attempt > 100) throw OutputError(where + ": cannot take the lock " + lock_path_);
  }
  const std::string holder = holderText() + "\n";
  if (::ftruncate(lock_fd_, 0) == 0) {
    const ssize_t w = ::pwrite(lock_fd_, holder.data(), holder.size(), 0);
    (void)w;  // the holder text only makes a busy message more helpful
  }
}

void OutputSet::unlock() noexcept {
  if (lock_fd_ < 0) return;
  ::unlink(lock_path_.c_str());  // while holding it: the next run creates a fresh one
  ::close(lock_fd_);
  lock_fd_ = -1;
}

void OutputSet::recover() {
  std::error_code ec;
  if (!fs::exists(staging_, ec)) return;
  const fs::path journal = fs::path(staging_) / kJournal;
  if (fs::exists(journal, ec)) {
    // An install that was cut: finish it.
    std::vector<Step> steps;
    std::ifstream f(journal);
    for (std::string line; std::getline(f, line);) {
      std::istringstream is(line);
      std::string kind, a, b;
      std::getline(is, kind, '\t');
      std::getline(is, a, '\t');
      std::getline(is, b, '\t');
      if (kind == "rename") steps.push_back({Step::Rename, a, b});
      if (kind == "remove") steps.push_back({Step::Remove, a, a});
      if (kind == "install") steps.push_back({Step::Install, a, a});
    }
    run(steps);
    log_ << "Finished installing the outputs of an interrupted run in " << dir_ << "\n";
  } else if (!options_.recording.empty()) {
    // A run that died: its recording is kept, the rest goes.
    for (const std::string& staged : {options_.recording, options_.recording + ".tmp"}) {
      const fs::path p = fs::path(staging_) / staged;
      if (!fs::is_regular_file(p, ec) || fs::file_size(p, ec) == 0) continue;
      const std::string kept = keptName(options_.recording, p.string());
      fs::rename(p, fs::path(dir_) / kept);
      const fs::path stats = fs::path(staging_) / options_.recording_companion;
      if (!options_.recording_companion.empty() && fs::is_regular_file(stats, ec)) {
        const auto [stem, ext] = splitExtension(kept);
        fs::rename(stats, fs::path(dir_) / (stem + "." + options_.recording_companion));
      }
      log_ << "Kept the recording of an interrupted run as " << joined(dir_, kept)
           << " (it may be cut short: freeinit --salvage reads it up to its last whole record)\n";
      break;
    }
  }
  fs::remove_all(staging_);
}

std::string OutputSet::keptRecordingName(const std::string& recording) const {
  return keptName(recording, joined(dir_, recording));
}

std::string OutputSet::keptName(const std::string& recording, const std::string& stamped) const {
  const auto [stem, ext] = splitExtension(recording);
  const std::string base = stem + "." + stampOf(stamped);
  std::error_code ec;
  std::string name = base + ext;
  for (int k = 2; fs::exists(fs::path(dir_) / name, ec); ++k)
    name = base + "-" + std::to_string(k) + ext;
  return name;
}

void OutputSet::holdReserve() noexcept {
  if (options_.reserve_bytes == 0 || reserve_held_ || done_) return;
  const std::string p = joined(staging_, kReserve);
  const int fd = ::open(p.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  if (fd < 0) return;
  const bool held = ::posix_fallocate(fd, 0, static_cast<off_t>(options_.reserve_bytes)) == 0;
  ::close(fd);
  if (held)
    reserve_held_ = true;
  else
    ::unlink(p.c_str());  // no room: the run goes on without
}

void OutputSet::releaseReserve() noexcept {
  if (!reserve_held_) return;
  ::unlink(joined(staging_, kReserve).c_str());
  reserve_held_ = false;
}

std::string OutputSet::finalPath(const std::string& name) const { return joined(dir_, name); }

std::string OutputSet::path(const std::string& name) {
  if (name.empty() || fs::path(name).is_absolute() || name.find("..") != std::string::npos)
    throw std::logic_error("output name '" + name + "' is not relative to the output folder");
  const fs::path p = fs::path(staging_) / name;
  fs::create_directories(p.parent_path());
  return p.string();
}

bool OutputSet::noSpace(const std::string& message) const {
  std::error_code ec;
  return message.find(std::strerror(ENOSPC)) != std::string::npos ||
         fileSystemFull(fs::exists(staging_, ec) ? staging_ : dir_);
}

std::string OutputSet::describe(const std::string& name, const std::string& message) const {
  std::string m = message;
  replaceAll(m, staging_ + "/", dir_ + "/");
  replaceAll(m, staging_, dir_);
  if (noSpace(m))
    return finalPath(name) + ": cannot be written: no space left on the device (" + dir_ +
           " is full); " + leftBehind();
  return m;
}

bool OutputSet::earlierSetPresent() const {
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir_, ec)) {
    const std::string n = e.path().filename().string();
    if (e.path() == fs::path(staging_) || e.path() == fs::path(lock_path_)) continue;
    if (n == options_.recording || n == options_.recording_companion ||
        owned(n, e.is_directory(ec)))
      return true;
  }
  return false;
}

std::vector<OutputSet::Step> OutputSet::keepSteps() const {
  std::vector<Step> steps;
  if (options_.recording.empty()) return steps;
  std::error_code ec;
  const fs::path staging(staging_);
  const std::string staging_name = staging.filename().string() + "/";
  for (const std::string& staged : {options_.recording, options_.recording + ".tmp"}) {
    const fs::path p = staging / staged;
    if (!fs::is_regular_file(p, ec)) continue;
    // In place of the earlier set once it is replaced, else beside it, under a name with its time.
    const bool in_place = replaced_ && !fs::exists(fs::path(dir_) / options_.recording, ec);
    const std::string kept =
        in_place ? options_.recording : keptName(options_.recording, p.string());
    steps.push_back({Step::Rename, staging_name + staged, kept});
    const std::string& companion = options_.recording_companion;
    if (!companion.empty() && fs::is_regular_file(staging / companion, ec)) {
      const std::string kept_companion =
          in_place ? companion : splitExtension(kept).first + "." + companion;
      steps.push_back({Step::Rename, staging_name + companion, kept_companion});
    }
    break;
  }
  return steps;
}

std::string OutputSet::leftBehind() const {
  std::vector<std::string> ours = installed_, moved;
  for (const Step& s : keepSteps())
    (replaced_ && (s.to == options_.recording || s.to == options_.recording_companion) ? ours
                                                                                       : moved)
        .push_back(s.to);
  const auto list = [](const std::vector<std::string>& names) {
    std::string text;
    for (std::size_t i = 0; i < names.size(); ++i)
      text += (i == 0 ? "" : i + 1 == names.size() ? " and " : ", ") + names[i];
    return text;
  };
  std::string text;
  if (!ours.empty()) {
    text = "this run's " + list(ours) + (ours.size() > 1 ? " are in " : " is in ") + dir_ +
           ", its other outputs are not";
    if (!moved.empty()) text += "; its recording is kept as " + joined(dir_, moved.front());
    return text;
  }
  if (!moved.empty()) {
    text = "this run's recording is kept as " + joined(dir_, moved.front());
    if (moved.size() > 1) text += " with its statistics " + moved[1];
  } else {
    text = "nothing of this run is left in " + dir_;
  }
  if (earlierSetPresent()) text += ", the earlier outputs there are as they were";
  return text;
}

void OutputSet::write(const std::string& name,
                      const std::function<void(const std::string& path)>& fill) {
  throwIfStopRequested();
  const std::string p = path(name);
  try {
    fill(p);
  } catch (const Interrupted&) {
    throw;
  } catch (const std::exception& e) {
    throw OutputError(describe(name, e.what()));
  }
}

bool OutputSet::owned(const std::string& entry, bool is_dir) const {
  for (const auto& pattern : options_.owned) {
    const bool dir_pattern = !pattern.empty() && pattern.back() == '/';
    if (dir_pattern != is_dir) continue;
    const std::string p = dir_pattern ? pattern.substr(0, pattern.size() - 1) : pattern;
    if (::fnmatch(p.c_str(), entry.c_str(), 0) == 0) return true;
  }
  return false;
}

std::vector<OutputSet::Step> OutputSet::replacementSteps(
    const std::vector<std::string>& installing) const {
  std::vector<Step> steps;
  std::error_code ec;
  if (!replaced_) {
    const fs::path dir(dir_);
    bool companion_renamed = false;
    const std::string& companion = options_.recording_companion;
    const bool has_companion = !companion.empty() && fs::is_regular_file(dir / companion, ec);
    if (!options_.recording.empty() && fs::is_regular_file(dir / options_.recording, ec)) {
      const std::string kept = keptRecordingName(options_.recording);
      steps.push_back({Step::Rename, options_.recording, kept});
      if (has_companion) {
        steps.push_back({Step::Rename, companion, splitExtension(kept).first + "." + companion});
        companion_renamed = true;
      }
    } else if (has_companion) {
      // Statistics of a recording kept under another name: kept too, with their own time.
      steps.push_back({Step::Rename, companion, keptName(companion, joined(dir_, companion))});
      companion_renamed = true;
    }
    for (const auto& e : fs::directory_iterator(dir, ec)) {
      const std::string n = e.path().filename().string();
      if (e.path() == fs::path(staging_) || e.path() == fs::path(lock_path_)) continue;
      if (companion_renamed && n == options_.recording_companion) continue;
      const bool is_dir = e.is_directory(ec);
      if (!owned(n, is_dir)) continue;
      // A file this install replaces goes by the rename itself (never absent meanwhile).
      const bool replaced_by_rename =
          !is_dir && std::find(installing.begin(), installing.end(), n) != installing.end();
      if (!replaced_by_rename) steps.push_back({Step::Remove, n, n});
    }
  }
  for (const auto& n : installing) steps.push_back({Step::Install, n, n});
  return steps;
}

void OutputSet::run(const std::vector<Step>& steps) {
  if (steps.empty()) return;
  const fs::path dir(dir_), staging(staging_);
  const fs::path journal = staging / kJournal;
  std::error_code ec;
  const bool journaled = fs::is_directory(staging, ec) && !fs::exists(journal, ec);
  if (journaled) {
    const fs::path tmp = staging / (std::string(kJournal) + ".tmp");
    {
      std::ofstream f(tmp, std::ios::trunc);
      for (const auto& s : steps)
        f << (s.kind == Step::Rename   ? "rename"
              : s.kind == Step::Remove ? "remove"
                                       : "install")
          << "\t" << s.from << "\t" << s.to << "\n";
      f.flush();
      if (!f) {
        f.close();
        fs::remove(tmp, ec);
        throw OutputError(describe(kJournal, dir_ + ": cannot write the install journal: " +
                                                 std::string(std::strerror(errno))));
      }
    }
    fs::rename(tmp, journal);
  }
  try {
    for (const auto& s : steps) {
      switch (s.kind) {
        case Step::Rename:
          if (fs::exists(dir / s.from, ec) && !fs::exists(dir / s.to, ec))
            fs::rename(dir / s.from, dir / s.to);
          break;
        case Step::Remove:
          fs::remove_all(dir / s.from);
          break;
        case Step::Install: {
          const fs::path from = staging / s.from, to = dir / s.from;
          if (!fs::exists(from, ec)) break;
          if (fs::exists(to, ec) && (fs::is_directory(to, ec) || fs::is_directory(from, ec)))
            fs::remove_all(to);
          fs::rename(from, to);
          break;
        }
      }
    }
  } catch (const fs::filesystem_error& e) {
    throw OutputError(dir_ + ": installing the outputs failed: " + e.what());
  }
  if (journaled) fs::remove(journal, ec);
}

void OutputSet::install(const std::vector<std::string>& names) {
  if (done_) throw std::logic_error(dir_ + ": output set already closed");
  run(replacementSteps(names));
  replaced_ = true;
  for (const auto& n : names)
    if (std::find(installed_.begin(), installed_.end(), n) == installed_.end())
      installed_.push_back(n);
}

void OutputSet::commit() {
  if (done_) throw std::logic_error(dir_ + ": output set already closed");
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(staging_)) {
    const std::string n = e.path().filename().string();
    if (n == kJournal || n == kReserve) continue;
    names.push_back(n);
  }
  const auto rank = [&](const std::string& n) {
    const auto& last = options_.install_last;
    const auto it = std::find(last.begin(), last.end(), n);
    return it == last.end() ? -1 : static_cast<int>(it - last.begin());
  };
  std::sort(names.begin(), names.end(), [&](const std::string& a, const std::string& b) {
    return std::make_pair(rank(a), a) < std::make_pair(rank(b), b);
  });
  releaseReserve();  // room for the journal, should the disk be full
  install(names);
  std::error_code ec;
  fs::remove_all(staging_, ec);
  unlock();
  done_ = true;
}

void OutputSet::abandon() noexcept {
  if (done_) return;
  std::error_code ec;
  releaseReserve();
  // This run's recording (and its statistics) stay: a recording is never lost. The earlier set
  // stays as it was unless this run's replaced it already (install()).
  std::vector<Step> keep;
  try {
    keep = keepSteps();
    run(keep);
  } catch (...) {
    // The journal could not be written: the renames alone.
    for (const Step& s : keep) fs::rename(fs::path(dir_) / s.from, fs::path(dir_) / s.to, ec);
  }
  done_ = true;
  bool kept = true;
  for (const Step& s : keep) kept = kept && !fs::exists(fs::path(dir_) / s.from, ec);
  if (kept) {
    fs::remove_all(staging_, ec);
  } else {
    // Left for the next run, which moves it out (recover()); the rest goes.
    std::vector<fs::path> others;
    for (const auto& e : fs::directory_iterator(staging_, ec)) {
      const std::string n = e.path().filename().string();
      if (n != options_.recording && n != options_.recording + ".tmp" &&
          n != options_.recording_companion)
        others.push_back(e.path());
    }
    for (const auto& p : others) fs::remove_all(p, ec);
  }
  unlock();
  for (const auto& d : created_dirs_) fs::remove(d, ec);  // only empty ones go
}

}  // namespace freeinit::app_support
