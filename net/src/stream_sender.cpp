#include <freeinit/net/stream_sender.h>

#include <chrono>
#include <ostream>
#include <stdexcept>

namespace freeinit::net {

void printStats(std::ostream& o, const SenderStats& s) {
  o << "datagrams   = " << s.datagrams << "\n"
    << "bytes       = " << s.bytes << "\n"
    << "imu_samples = " << s.imu_samples << "\n"
    << "frames      = " << s.frames << "\n"
    << "sessions    = " << s.sessions << "\n"
    << "dropped     = " << s.dropped << "\n"
    << "duplicated  = " << s.duplicated << "\n"
    << "reordered   = " << s.reordered << "\n"
    << "corrupted   = " << s.corrupted << "\n"
    << "garbage     = " << s.garbage << "\n"
    << "truncated   = " << s.truncated << "\n"
    << "refused     = " << s.refused << "\n";
}

StreamSender::StreamSender(const std::string& address, std::uint16_t port, std::size_t max_datagram,
                           const FaultParams& faults)
    : max_datagram_(max_datagram), faults_(faults), rng_(faults.seed) {
  pointsPerChunk(max_datagram_);  // validates the size
  for (double p : {faults.drop, faults.duplicate, faults.reorder, faults.corrupt, faults.truncate})
    if (!(p >= 0 && p <= 1)) throw std::invalid_argument("fault probabilities must be in [0, 1]");
  socket_.connect(address, port);
  restart();
}

void StreamSender::restart() {
  flush();
  // Independent of the fault seed: two senders started together still get different sessions.
  std::random_device rd;
  const auto t = static_cast<std::uint64_t>(
      std::chrono::high_resolution_clock::now().time_since_epoch().count());
  session_ = (static_cast<std::uint64_t>(rd()) << 32) ^ rd() ^ t;
  seq_ = 0;
  next_frame_id_ = 0;
  ++stats_.sessions;
}

bool StreamSender::chance(double p) {
  return p > 0 && std::uniform_real_distribution<double>(0.0, 1.0)(rng_) < p;
}

void StreamSender::sendImu(const ImuMessage& s) {
  emit(encodeImu({s}, session_, seq_));
  ++stats_.imu_samples;
}

void StreamSender::sendFrame(FrameMessage f) {
  f.frame_id = next_frame_id_++;
  for (auto& d : encodeFrame(f, session_, seq_, max_datagram_)) emit(std::move(d));
  ++stats_.frames;
}

void StreamSender::sendFrameChunk(const FrameMessage& f, std::size_t chunk) {
  emit(encodeFrameChunk(f, chunk, session_, seq_, max_datagram_));
  if (chunk + 1 == chunkCount(f.points.size(), max_datagram_)) ++stats_.frames;
}

void StreamSender::sendEndOfStream() {
  flush();
  raw(encodeEndOfStream(session_, seq_));  // never faulted: the receiver's loss count is exact
}

void StreamSender::sendGarbage(int n) {
  std::uniform_int_distribution<int> byte(0, 255);
  std::uniform_int_distribution<std::size_t> size(1, 256);
  for (int i = 0; i < n; ++i) {
    std::vector<std::uint8_t> d(size(rng_));
    for (auto& b : d) b = static_cast<std::uint8_t>(byte(rng_));
    if (i % 2 == 0 && d.size() >= 4) {  // a valid magic, so that the deeper checks are exercised
      for (int k = 0; k < 4; ++k)
        d[static_cast<std::size_t>(k)] = static_cast<std::uint8_t>(kMagic >> (8 * k));
    }
    raw(d);
    ++stats_.garbage;
  }
}

void StreamSender::flush() {
  if (held_) {
    raw(*held_);
    held_.reset();
  }
}

void StreamSender::emit(std::vector<std::uint8_t> d) {
  if (chance(faults_.drop)) {
    ++stats_.dropped;
    return;
  }
  if (chance(faults_.corrupt)) {
    const std::size_t i = std::uniform_int_distribution<std::size_t>(0, d.size() - 1)(rng_);
    d[i] ^= static_cast<std::uint8_t>(1 + std::uniform_int_distribution<int>(0, 254)(rng_));
    ++stats_.corrupted;
  }
  if (d.size() > 1 && chance(faults_.truncate)) {
    d.resize(std::uniform_int_distribution<std::size_t>(1, d.size() - 1)(rng_));
    ++stats_.truncated;
  }
  if (!held_ && chance(faults_.reorder)) {
    held_ = std::move(d);  // goes out after the next datagram
    ++stats_.reordered;
    return;
  }
  raw(d);
  if (chance(faults_.duplicate)) {
    raw(d);
    ++stats_.duplicated;
  }
  flush();
}

void StreamSender::raw(const std::vector<std::uint8_t>& d) {
  if (socket_.send(d.data(), d.size())) {
    ++stats_.datagrams;
    stats_.bytes += d.size();
  } else {
    ++stats_.refused;
  }
}

}  // namespace freeinit::net
