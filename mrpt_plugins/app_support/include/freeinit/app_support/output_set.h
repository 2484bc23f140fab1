// A run's outputs as one set, the same way in every app.
//
// Staging: every output is written into a staging folder beside its place
// (`<dir>/.freeinit.staging/` for an output folder, `<dir>/.<name>.freeinit.staging/` for a set of
// files named after one output, e.g. freeinit-sim's <name>.rawlog, <name>.truth.csv, ...) and
// installed when the run is complete: the earlier run's outputs of ours are removed and the staged
// entries renamed into place (renames within one file system: nothing is copied). Before the first
// rename a journal listing every step is written into the staging folder, so that a run that finds
// it (the machine lost power while installing) finishes the install first. Signals cannot split an
// install: the apps' handlers only record them (stop_signal.h).
//
// The rule users can rely on: after a run, the folder holds the complete outputs of that run, or
// none of ours. A run that fails, is interrupted or finds a full disk removes its staging folder
// and the earlier run's outputs, so that nothing there passes for its result. What is not ours is
// never touched (only the names an app of this project writes are removed), and a live recording
// is never deleted: the set that replaces an earlier one renames the earlier recording (and its
// stream statistics) with the time it was last written, e.g. live.20251201-215503.rawlog.
//
// Lock: two runs on one set cannot interleave. The set holds an exclusive lock (flock) on
// `<dir>/.freeinit.lock` (or `.<name>.freeinit.lock`) from construction to the end; a second run
// fails at once with one line naming the folder and the holder (its pid and command line). The
// lock file is removed when the set is released, so no file of ours is left behind but the
// outputs.
#pragma once

#include <functional>
#include <iosfwd>
#include <stdexcept>
#include <string>
#include <vector>

namespace freeinit::app_support {

/// Writing or installing an output failed (the message names the output file, and says "no
/// space left on the device" when the disk is full).
class OutputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Another run holds the set's lock.
class OutputBusy : public OutputError {
 public:
  using OutputError::OutputError;
};

struct OutputSetOptions {
  /// What of `dir` belongs to the set (is removed when it is replaced): names relative to
  /// `dir`, a trailing '/' for a folder, '*' matching any characters (e.g. "start_*/").
  std::vector<std::string> owned;
  /// A live recording in `dir` ("live.rawlog"; "" for none): staged like every output, never
  /// deleted. The one of an earlier run is renamed (with its time) when this set replaces it; one
  /// left in the staging folder of a run that died is moved out the same way.
  std::string recording;
  /// Belongs to the recording (renamed with it): "stream_stats.ini".
  std::string recording_companion;
  /// Installed after every other entry (the file readers wait for, e.g. initial_state.ini).
  std::vector<std::string> install_last;
};

class OutputSet {
 public:
  /// Takes the lock (throws OutputBusy), finishes or discards what an interrupted run left in the
  /// staging folder, and creates the staging folder (and `dir` when missing). `name`: "" for the
  /// folder's own set, else the name the lock and staging folder are called after. Notes (an
  /// interrupted install finished, a recording kept) go to `log`.
  OutputSet(std::string dir, std::string name, OutputSetOptions options, std::ostream& log);
  /// Without commit(): abandon().
  ~OutputSet();
  OutputSet(const OutputSet&) = delete;
  OutputSet& operator=(const OutputSet&) = delete;

  const std::string& dir() const { return dir_; }
  /// Where `name` (relative to dir(), may hold '/') goes when installed.
  std::string finalPath(const std::string& name) const;
  /// Where to write `name` now: in the staging folder (its parent folders are created).
  std::string path(const std::string& name);

  /// Runs `fill` on path(name) after checking for a stop request; an error (other than
  /// Interrupted) becomes an OutputError naming the final file (describe()).
  void write(const std::string& name, const std::function<void(const std::string& path)>& fill);

  /// Installs the staged `names` now (the first install replaces the earlier set: every entry of
  /// ours is removed, its recording renamed), the others staying staged. For the online app's
  /// state, written the moment the window closes while the rest follows at the stream's end.
  void install(const std::vector<std::string>& names);
  /// Installs everything staged (install_last entries last), removes the staging folder and
  /// releases the lock.
  void commit();
  /// Removes the staging folder and the earlier set (its recording renamed, as install() does),
  /// then releases the lock; folders created for the set are removed when empty. No-throw.
  void abandon() noexcept;

  /// `message` of a failed write with staged paths replaced by final ones, and "no space left on
  /// the device" when the file system of the set is full.
  std::string describe(const std::string& name, const std::string& message) const;

  /// What an earlier run's recording of `recording` would be renamed to now (for messages).
  std::string keptRecordingName(const std::string& recording) const;

 private:
  struct Step {
    enum Kind { Rename, Remove, Install } kind;
    std::string from, to;  ///< names relative to dir_ (Install: from = to = the name)
  };
  void lock();
  void unlock() noexcept;
  void recover();
  std::vector<Step> replacementSteps(const std::vector<std::string>& installing) const;
  void run(const std::vector<Step>& steps);
  bool owned(const std::string& entry, bool is_dir) const;

  std::string dir_, name_, staging_, lock_path_;
  OutputSetOptions options_;
  std::ostream& log_;
  int lock_fd_ = -1;
  std::vector<std::string> created_dirs_;  ///< made for the set, innermost first
  bool replaced_ = false;                  ///< the earlier set is gone
  bool done_ = false;                      ///< committed or abandoned
};

}  // namespace freeinit::app_support
