// Sends a live stream in the wire format over UDP, optionally with injected network faults
// (for tests and for checking a receiver): lost, duplicated, reordered, corrupted and truncated
// datagrams, garbage datagrams, and sender restarts (a new session id).
#pragma once

#include <freeinit/net/udp_socket.h>
#include <freeinit/net/wire_format.h>

#include <cstdint>
#include <iosfwd>
#include <optional>
#include <random>
#include <string>
#include <vector>

namespace freeinit::net {

/// Per-datagram fault probabilities in [0, 1].
struct FaultParams {
  double drop = 0;       ///< the datagram is not sent
  double duplicate = 0;  ///< sent twice
  double reorder = 0;    ///< held back and sent after the next datagram
  double corrupt = 0;    ///< one byte flipped after the CRC was computed
  double truncate = 0;   ///< cut short (1 byte to all but the last), as a broken link delivers
  std::uint64_t seed = 1;
};

/// What the sender did (datagrams, and the faults it injected).
struct SenderStats {
  std::uint64_t datagrams = 0, bytes = 0;
  std::uint64_t imu_samples = 0, frames = 0, sessions = 0;
  std::uint64_t dropped = 0, duplicated = 0, reordered = 0, corrupted = 0, garbage = 0;
  std::uint64_t truncated = 0;
  std::uint64_t refused = 0;  ///< the kernel refused to send (e.g. no listener)
};
void printStats(std::ostream& o, const SenderStats& s);

class StreamSender {
 public:
  /// `max_datagram`: bytes per datagram (kMinDatagram..kMaxDatagram). 1472 fits an Ethernet MTU
  /// without IP fragmentation; loopback takes up to 65507.
  StreamSender(const std::string& address, std::uint16_t port, std::size_t max_datagram = 8192,
               const FaultParams& faults = {});

  void sendImu(const ImuMessage& s);
  void sendFrame(FrameMessage f);  ///< frame_id is assigned here
  /// Sends one chunk of a frame (chunkCount() of them, in order), e.g. when its points have been
  /// measured. The caller sets f.frame_id, different from the previous frame's.
  void sendFrameChunk(const FrameMessage& f, std::size_t chunk);
  /// Ends the session with an end-of-stream marker (carries the number of datagrams sent).
  void sendEndOfStream();
  /// Simulates a sender restart: a new random session id, sequence numbers from 0 again.
  void restart();
  /// Sends `n` random datagrams that are not valid packets (some with a valid magic).
  void sendGarbage(int n);
  /// Sends a datagram held back for reordering, if any.
  void flush();

  std::uint64_t session() const { return session_; }
  std::size_t maxDatagram() const { return max_datagram_; }
  const SenderStats& stats() const { return stats_; }

 private:
  void emit(std::vector<std::uint8_t> d);
  void raw(const std::vector<std::uint8_t>& d);
  bool chance(double p);

  UdpSocket socket_;
  std::size_t max_datagram_;
  FaultParams faults_;
  std::mt19937_64 rng_;
  std::uint64_t session_ = 0, seq_ = 0;
  std::uint32_t next_frame_id_ = 0;
  std::optional<std::vector<std::uint8_t>> held_;
  SenderStats stats_;
};

}  // namespace freeinit::net
