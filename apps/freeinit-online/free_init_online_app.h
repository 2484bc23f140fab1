// Free-Init on a live stream: `freeinit-online <config.ini> [--port N] [--out DIR]`. Receives the
// Doppler LiDAR + IMU wire format (docs/wire_format.md), feeds the same observation handler as the
// offline app, in arrival order, writes initial_state.ini (atomically) the moment the window
// closes (replacing the earlier run's outputs then, not before), and records everything it fed to
// a rawlog, so that `freeinit` on that rawlog gives the same result. When the stream ends it
// writes the other outputs (static map, trajectory, ...) as the offline app does.
#pragma once

#include <freeinit/app_support/app_config.h>
#include <freeinit/initial_state.h>
#include <freeinit/net/stream_source.h>

#include <functional>
#include <iosfwd>
#include <memory>
#include <string>

namespace freeinit::apps {

struct FreeInitOnlineAppParams {
  std::string config_file;
  std::string out_dir = "freeinit_online_out";
  std::string record = "live.rawlog";  ///< recording, relative to out_dir ("" = none)
  net::UdpSourceParams source;         ///< address, port, queue bounds, reorder timeouts
  double wait_first = 0;      ///< [s] give up if no data arrives for this long (0: wait forever)
  double idle_timeout = 2.0;  ///< [s] once data flowed: end after this long without any
  double max_duration = 0;    ///< [s] end after this long (0: no limit)
  bool stop_at_end_of_stream = true;  ///< end at the sender's end-of-stream marker
  bool stop_when_ready = false;       ///< end as soon as the state is written
};

/// Timings of the moment the state became ready [s].
struct OnlineLatency {
  double total = 0;      ///< receipt of the last needed datagram -> initial_state.ini renamed
  double queue = 0;      ///< receipt -> handed to the estimator (queue wait and conversion)
  double estimator = 0;  ///< the process() call that closed the window
  double write = 0;      ///< writing and renaming initial_state.ini
};

class FreeInitOnlineApp {
 public:
  FreeInitOnlineAppParams params;
  /// Called once the socket listens, with the bound port (useful with port 0).
  std::function<void(std::uint16_t)> on_listening;
  /// Another data source (e.g. a vendor SDK) instead of the UDP receiver; run() takes it.
  std::unique_ptr<net::StreamSource> source;

  /// Runs until the end of the stream (see params). Bad configuration throws before listening;
  /// observations the estimator rejects throw InputError after the recording is closed; a
  /// recording whose write fails (a full disk) ends the stream and throws OutputError once it is
  /// closed at its last whole record with its statistics (the message says what is left).
  /// Returns 0 initialized, 3 not initialized (reason in initial_state.ini).
  int run(std::ostream& log);
  /// The command line (`main` of freeinit-online): parses it, runs, returns the exit code.
  static int main(int argc, char** argv);

  // Filled by run().
  app_support::AppConfig config;
  InitResult result;
  bool ready_live = false;  ///< the state was written while the stream ran (not at its end)
  OnlineLatency latency;
  net::SourceStats stats;
  /// The source's statistics when the state was written (ready_live): data lost before then
  /// may have been inside the window.
  net::SourceStats stats_at_ready;
  std::size_t recorded = 0;  ///< observations recorded (and fed, up to the ready point)
  std::string record_path;   ///< full path of the recording
};

}  // namespace freeinit::apps
