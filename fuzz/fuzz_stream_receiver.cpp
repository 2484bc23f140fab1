// Fuzz harness: a sequence of datagrams through the stream receiver. Input: records of
//   u8 flags, u16 length (little-endian), `length` bytes (one datagram),
// flags bits 0-5: milliseconds the clock advances before the datagram; bit 6: tick() after it;
// bit 7: make its length field and CRC consistent (wire_patch.h). A last tick 10 s
// later flushes what is held. Invariants of the output: IMU and frame stamps strictly increasing,
// frames complete (as many points as declared, within the format's maximum), the malformed count
// the sum of its reasons, and the events no more than the datagrams could carry.
#include <freeinit/net/stream_receiver.h>

#include <vector>

#include "harness.h"
#include "wire_patch.h"

namespace freeinit::fuzz {

std::string fuzzOne(const std::uint8_t* data, std::size_t size) {
  net::ReceiverParams params;
  params.reorder_window = 64;  // small enough that gaps are given up within an input
  net::StreamReceiver rx(params);
  auto now = net::SteadyClock::time_point{} + std::chrono::hours(1);
  std::vector<net::StreamEvent> out;
  std::int64_t last_imu = -1, last_frame = -1;
  std::size_t imu = 0, frames = 0, datagrams = 0, total_points_in = 0;
  auto drain = [&] {
    for (const auto& e : out) {
      if (e.kind == net::StreamEvent::Kind::Imu) {
        if (e.imu.stamp_ns <= last_imu) broken("IMU stamps do not increase");
        last_imu = e.imu.stamp_ns;
        ++imu;
      } else if (e.kind == net::StreamEvent::Kind::Frame) {
        if (e.frame.stamp_ns <= last_frame) broken("frame stamps do not increase");
        if (e.frame.points.empty() || e.frame.points.size() > net::kMaxFramePoints)
          broken("frame size out of range");
        last_frame = e.frame.stamp_ns;
        ++frames;
      }
    }
    out.clear();
  };
  std::size_t pos = 0;
  while (size - pos >= 3) {
    const std::uint8_t flags = data[pos];
    const std::size_t len =
        std::min<std::size_t>(data[pos + 1] | (data[pos + 2] << 8), size - pos - 3);
    std::vector<std::uint8_t> d(data + pos + 3, data + pos + 3 + len);
    pos += 3 + len;
    if (flags & 0x80) patchLengthAndCrc(d);
    now += std::chrono::milliseconds(flags & 0x3F);
    rx.push(d.data(), d.size(), now, out);
    ++datagrams;
    total_points_in += d.size() / net::kPointBytes;
    if (flags & 0x40) rx.tick(now, out);
    drain();
  }
  rx.tick(now + std::chrono::seconds(10), out);
  drain();
  const net::ReceiverStats& s = rx.stats();
  std::uint64_t reasons = 0;
  for (auto r : s.malformed_by_reason) reasons += r;
  if (reasons != s.malformed) broken("malformed != sum of its reasons");
  if (s.datagrams != datagrams) broken("datagram count");
  if (imu != s.imu_samples || frames != s.frames) broken("event counts differ from the stats");
  if (imu > size / net::kImuSampleBytes) broken("more IMU samples than the input holds");
  return "ok: " + std::to_string(datagrams) + " datagrams, " + std::to_string(imu) +
         " IMU samples, " + std::to_string(frames) + " frames, " + std::to_string(s.malformed) +
         " malformed, " + std::to_string(s.anomalies()) + " anomalies";
}

}  // namespace freeinit::fuzz
