// Turns received datagrams (in whatever order, duplicated, corrupted or lost) into an ordered
// stream of IMU samples and complete LiDAR frames, counting every anomaly. Pure logic, no socket:
// the caller passes each datagram with its receipt time and calls tick() periodically.
//
// Guarantees on the output: datagrams are handled in sequence order within a session (a bounded
// reorder buffer waits for gaps, up to `reorder_window` datagrams or `reorder_timeout`); frames
// are emitted complete or not at all (a frame missing chunks is dropped and counted); IMU and
// frame stamps strictly increase across the whole output, even across sender restarts (older
// samples are dropped and counted). Memory is bounded by the reorder window plus one frame.
#pragma once

#include <freeinit/net/wire_format.h>

#include <chrono>
#include <cstdint>
#include <deque>
#include <iosfwd>
#include <map>
#include <optional>
#include <set>
#include <utility>
#include <vector>

namespace freeinit::net {

using SteadyClock = std::chrono::steady_clock;

struct ReceiverParams {
  std::size_t reorder_window = 1024;  ///< [datagrams] held while waiting for a missing one
  double reorder_timeout = 0.05;      ///< [s] longest wait for a missing datagram
  double frame_timeout = 0.5;         ///< [s] an incomplete frame with no new chunk is dropped
};

/// Counters of everything the receiver saw. "Lost" datagrams are sequence numbers skipped.
struct ReceiverStats {
  std::uint64_t datagrams = 0, bytes = 0;
  std::uint64_t malformed = 0;  ///< bad size, magic, version, CRC or content (sum of the next)
  std::uint64_t malformed_by_reason[7] = {};  ///< indexed by DecodeError
  std::uint64_t duplicates = 0;               ///< a sequence number seen before
  std::uint64_t out_of_order = 0;  ///< arrived after a higher sequence number (then reordered)
  std::uint64_t late = 0;          ///< arrived after its gap was given up: dropped
  std::uint64_t lost = 0;          ///< sequence numbers never received (gaps given up)
  /// Datagrams the first session sent before the receiver started (its first sequence number):
  /// not a network loss, reported apart.
  std::uint64_t joined_late = 0;
  std::uint64_t sessions = 0;       ///< sender sessions seen (a restart adds one)
  std::uint64_t stale_session = 0;  ///< datagrams of a session already replaced: dropped
  std::uint64_t end_of_stream = 0;  ///< end-of-stream markers received
  std::uint64_t imu_samples = 0;    ///< emitted
  std::uint64_t imu_stale = 0;      ///< not newer than the last emitted one: dropped
  /// Stamped far from the stream's clock (a glitch 10 days ahead): dropped, and not taken as
  /// the stream's last stamp, so the samples after it are not stale. The clock model is the
  /// median of stamp minus receipt time over the last 50 samples; far: beyond 0.5 s or 50
  /// sample intervals. An offset that persists over 1 s of receipt time is the sender's clock
  /// stepping: the model restarts from it.
  std::uint64_t imu_stamp_anomaly = 0;
  std::uint64_t frames = 0;               ///< complete frames emitted
  std::uint64_t frames_incomplete = 0;    ///< dropped for missing chunks (superseded or timed out)
  std::uint64_t frames_stale = 0;         ///< not newer than the last emitted frame: dropped
  std::uint64_t frames_inconsistent = 0;  ///< chunks of one frame disagreeing: dropped

  /// Datagrams or data dropped for any reason (everything but a clean stream).
  std::uint64_t anomalies() const {
    return malformed + duplicates + late + lost + stale_session + imu_stale + imu_stamp_anomaly +
           frames_incomplete + frames_stale + frames_inconsistent;
  }
};
/// "key = value" lines, one per counter.
void printStats(std::ostream& o, const ReceiverStats& s);

/// One item of the ordered output.
struct StreamEvent {
  enum class Kind { Imu, Frame, SessionStart, EndOfStream } kind = Kind::Imu;
  std::uint64_t session = 0;
  ImuMessage imu;
  FrameMessage frame;
  /// Receipt time of the datagram that completed this item (for latency measurements).
  SteadyClock::time_point received;
};

class StreamReceiver {
 public:
  explicit StreamReceiver(const ReceiverParams& params = {});

  /// Handles one datagram received at `now`; appends what became available to `out`.
  void push(const std::uint8_t* data, std::size_t n, SteadyClock::time_point now,
            std::vector<StreamEvent>& out);
  /// Applies the timeouts (reorder wait, incomplete frame) at `now`.
  void tick(SteadyClock::time_point now, std::vector<StreamEvent>& out);

  const ReceiverStats& stats() const { return stats_; }

 private:
  struct Held {
    Packet packet;
    SteadyClock::time_point received;
  };
  // A frame being reassembled. Chunks are kept as they arrive, and the frame is built when the
  // last one is in: memory follows the points received (never more than the frame declares), not
  // the declared size, which a single corrupt-but-CRC-valid datagram would otherwise allocate.
  struct Assembly {
    FrameMessage frame;  ///< id, stamp and extrinsics; points filled when complete
    std::uint32_t total_points = 0;
    std::uint16_t chunk_count = 0;
    /// Per chunk index: its first point index and its points.
    std::map<std::uint16_t, std::pair<std::uint32_t, std::vector<DopplerPoint>>> chunks;
    std::uint64_t received_points = 0;
    SteadyClock::time_point last_chunk;
  };

  void startSession(std::uint64_t session, SteadyClock::time_point now,
                    std::vector<StreamEvent>& out);
  void releaseInOrder(std::vector<StreamEvent>& out);
  void skipGap(std::vector<StreamEvent>& out);
  void handle(Packet& p, SteadyClock::time_point received, std::vector<StreamEvent>& out);
  void handleChunk(FrameChunk& c, SteadyClock::time_point received, std::vector<StreamEvent>& out);
  void dropAssembly();
  /// Whether an IMU stamp received at `received` fits the stream's clock model (updated with it
  /// if it does; see ReceiverStats::imu_stamp_anomaly).
  bool stampFitsClock(std::int64_t stamp_ns, SteadyClock::time_point received);

  ReceiverParams params_;
  ReceiverStats stats_;
  std::optional<std::uint64_t> session_;
  std::deque<std::uint64_t> retired_sessions_;  ///< bounded
  std::uint64_t next_seq_ = 0, max_seq_seen_ = 0;
  bool released_in_session_ = false;    ///< a datagram of the current session was handled
  std::map<std::uint64_t, Held> held_;  ///< bounded by reorder_window
  std::set<std::uint64_t> skipped_;     ///< gaps given up (bounded), to tell late from dup
  std::optional<Assembly> assembly_;
  std::optional<std::int64_t> last_imu_ns_, last_frame_ns_;
  std::deque<double> clock_offsets_;  ///< [s] stamp - receipt time of the last samples
  std::deque<double> clock_stamps_;   ///< [s] their stamps
  std::optional<SteadyClock::time_point> anomalous_since_;  ///< first anomaly of a run
};

}  // namespace freeinit::net
