// Where live Doppler LiDAR + IMU data come from. The rawlog-grabber driver and the online app only
// see this interface: a vendor SDK can implement it instead of the UDP wire format.
#pragma once

#include <freeinit/net/stream_receiver.h>

#include <atomic>
#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace freeinit::net {

/// Counters of a source: the receiver's plus what the bounded queue had to drop.
struct SourceStats {
  ReceiverStats receiver;
  std::uint64_t queue_dropped_imu = 0;     ///< IMU samples dropped: the consumer was too slow
  std::uint64_t queue_dropped_frames = 0;  ///< frames dropped: the consumer was too slow
  std::uint64_t anomalies() const {
    return receiver.anomalies() + queue_dropped_imu + queue_dropped_frames;
  }
};
void printStats(std::ostream& o, const SourceStats& s);

class StreamSource {
 public:
  virtual ~StreamSource() = default;
  /// Starts receiving (in the background). Throws if the device/port cannot be opened.
  virtual void start() = 0;
  virtual void stop() = 0;
  /// Moves the items available now into `out` (appending), waiting up to `timeout_s` for the
  /// first one. Returns how many were added. Items are in stream order.
  virtual std::size_t poll(std::vector<StreamEvent>& out, double timeout_s) = 0;
  virtual SourceStats stats() const = 0;
};

struct UdpSourceParams {
  std::string address = "127.0.0.1";   ///< local address to listen on ("0.0.0.0": all)
  std::uint16_t port = 47800;          ///< 0: an ephemeral port (see UdpStreamSource::port())
  int receive_buffer = 16 << 20;       ///< [bytes] socket buffer asked for
  std::size_t max_queued_imu = 4000;   ///< bounded queue towards the consumer (20 s at 200 Hz)
  std::size_t max_queued_frames = 16;  ///< frames are large: a few only
  ReceiverParams receiver;
};

/// The wire format over UDP: a thread reads the socket into a StreamReceiver and a bounded queue.
/// When the consumer falls behind, new items are dropped and counted (never a silent gap).
class UdpStreamSource : public StreamSource {
 public:
  explicit UdpStreamSource(const UdpSourceParams& params);
  ~UdpStreamSource() override;

  void start() override;
  void stop() override;
  std::size_t poll(std::vector<StreamEvent>& out, double timeout_s) override;
  SourceStats stats() const override;
  /// The bound port (after start()).
  std::uint16_t port() const { return port_; }
  int receiveBufferGranted() const { return rcvbuf_; }

 private:
  void loop();
  void enqueue(std::vector<StreamEvent>& events);

  UdpSourceParams params_;
  std::unique_ptr<class UdpSocket> socket_;
  std::thread thread_;
  std::atomic<bool> running_{false};
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<StreamEvent> queue_;
  std::size_t queued_frames_ = 0, queued_imu_ = 0;
  SourceStats stats_;
  StreamReceiver receiver_;
  std::uint16_t port_ = 0;
  int rcvbuf_ = 0;
  std::string error_;  ///< a fatal error of the receiving thread, rethrown by poll()
};

}  // namespace freeinit::net
