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
// The rule users can rely on: earlier outputs are replaced only by a complete new set. A run that
// fails, is interrupted or finds a full disk before its set is installed removes its staging
// folder and leaves the earlier run's outputs as they were; after any run the folder holds one
// run's outputs, never a mix of two. What is not ours is never touched (only the names an app of
// this project writes are removed).
//
// A set installed in two steps (the online app: install() of the state the moment the
// initialization window closes, commit() of the rest when the stream ends) replaces the earlier
// set at its first install: from then on the folder holds this run's state, and a failure at the
// end leaves it with this run's recording and statistics, its other outputs missing (the message
// says which files are there: leftBehind()).
//
// Recordings are never deleted. The earlier run's recording (and its stream statistics) is
// renamed with the time it was last written, e.g. live.20251201-215503.rawlog and
// live.20251201-215503.stream_stats.ini, when a new set replaces it. This run's, when the run
// fails: installed under its own name if the set has replaced the earlier one, else moved out
// beside the earlier outputs under a name with its time; one left in the staging folder of a run
// that died (SIGKILL, a power loss) is moved out the same way by the next run, which says so.
//
// A full disk: a set with a reserve (OutputSetOptions::reserve_bytes, the online app's) holds that
// much room in its staging folder and releases it when the disk has filled, so that the recording
// can be ended at its last whole record, its statistics written and the install journaled.
//
// Lock: two runs on one set cannot interleave. The set holds an exclusive lock (flock) on
// `<dir>/.freeinit.lock` (or `.<name>.freeinit.lock`) from construction to the end; a second run
// fails at once with one line naming the folder and the holder (its pid and command line). The
// lock file is removed when the set is released, so no file of ours is left behind but the
// outputs.
#pragma once

#include <cstddef>
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
  /// Belongs to the recording (renamed with it, never deleted): "stream_stats.ini". Found
  /// without the recording (a recording under another name), it is renamed alone with its time.
  std::string recording_companion;
  /// Installed after every other entry (the file readers wait for, e.g. initial_state.ini).
  std::vector<std::string> install_last;
  /// [bytes] Room held in the staging folder for ending the run on a full disk (releaseReserve());
  /// 0: none.
  std::size_t reserve_bytes = 0;
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
  /// Ends a run that failed: keeps its staged recording and statistics (installed under their
  /// names if an install() replaced the earlier set, else moved out under a name with their
  /// time), removes the staging folder, leaves the earlier set as it was and releases the lock;
  /// folders created for the set are removed when empty. No-throw.
  void abandon() noexcept;

  /// What abandon() would leave in dir() now, for the message of a failure: "nothing of this run
  /// is left in d", "this run's recording is kept as d/live.20251201-215503.rawlog ...", or
  /// "this run's initial_state.ini, live.rawlog and stream_stats.ini are in d, its other outputs
  /// are not"; with ", the earlier outputs in d are as they were" when an earlier set is there.
  std::string leftBehind() const;

  /// `message` of a failed write with staged paths replaced by final ones; when the file system
  /// of the set is full, "<final path>: cannot be written: no space left on the device (<dir> is
  /// full); " and leftBehind().
  std::string describe(const std::string& name, const std::string& message) const;
  /// True when `message` says the disk is full or the file system of the set is (almost) full.
  bool noSpace(const std::string& message) const;

  /// What an earlier run's recording of `recording` would be renamed to now (for messages).
  std::string keptRecordingName(const std::string& recording) const;

  /// Gives back the room held for a full disk (reserve_bytes), e.g. before ending a recording the
  /// disk full stopped; holdReserve() takes it again when there is room. Both no-throw.
  void releaseReserve() noexcept;
  void holdReserve() noexcept;

 private:
  struct Step {
    enum Kind { Rename, Remove, Install } kind;
    std::string from, to;  ///< names relative to dir_ (Install: from = to = the name)
  };
  void lock();
  void unlock() noexcept;
  void recover();
  std::vector<Step> replacementSteps(const std::vector<std::string>& installing) const;
  /// What abandon() does with this run's staged recording and its statistics.
  std::vector<Step> keepSteps() const;
  /// "live.20251201-215503.rawlog": `recording` renamed with the time `stamped` was last written
  /// (a name not taken in dir_).
  std::string keptName(const std::string& recording, const std::string& stamped) const;
  bool earlierSetPresent() const;
  void run(const std::vector<Step>& steps);
  bool owned(const std::string& entry, bool is_dir) const;

  std::string dir_, name_, staging_, lock_path_;
  OutputSetOptions options_;
  std::ostream& log_;
  int lock_fd_ = -1;
  std::vector<std::string> created_dirs_;  ///< made for the set, innermost first
  std::vector<std::string> installed_;     ///< names of this run in place (install())
  bool replaced_ = false;                  ///< the earlier set is gone
  bool done_ = false;                      ///< committed or abandoned
  bool reserve_held_ = false;
};

}  // namespace freeinit::app_support
