#include <freeinit/net/stream_receiver.h>

#include <algorithm>
#include <cmath>
#include <ostream>

namespace freeinit::net {
namespace {
constexpr std::size_t kMaxRetiredSessions = 16;
constexpr std::size_t kMaxSkippedRemembered = 4096;
constexpr std::uint64_t kMaxSequenceJump = std::uint64_t{1} << 32;
/// The IMU clock model: the last this many accepted samples' stamp minus receipt time; it judges
/// a stamp once it holds at least kClockMinSamples.
constexpr std::size_t kClockSamples = 50, kClockMinSamples = 20;
/// [s] a stamp this far from the model (or 50 of the stream's sample intervals, if more) is an
/// anomaly; [s] an anomaly lasting this long in receipt time is the sender's clock stepping:
/// the model starts again from it.
constexpr double kClockTolerance = 0.5, kClockStepAfter = 1.0;

double seconds(SteadyClock::time_point t) {
  return std::chrono::duration<double>(t.time_since_epoch()).count();
}
}  // namespace

void printStats(std::ostream& o, const ReceiverStats& s) {
  o << "datagrams           = " << s.datagrams << "\n"
    << "bytes               = " << s.bytes << "\n"
    << "malformed           = " << s.malformed << "\n";
  static const char* const keys[7] = {"",
                                      "malformed_short  ",
                                      "malformed_magic  ",
                                      "malformed_version",
                                      "malformed_length ",
                                      "malformed_crc    ",
                                      "malformed_content"};
  for (int e = 1; e < 7; ++e)
    if (s.malformed_by_reason[e] > 0)
      o << keys[e] << "   = " << s.malformed_by_reason[e] << "  ; "
        << toString(static_cast<DecodeError>(e)) << "\n";
  o << "duplicates          = " << s.duplicates << "\n"
    << "out_of_order        = " << s.out_of_order << "\n"
    << "late                = " << s.late << "\n"
    << "lost                = " << s.lost << "\n"
    << "joined_late         = " << s.joined_late << "\n"
    << "sessions            = " << s.sessions << "\n"
    << "stale_session       = " << s.stale_session << "\n"
    << "end_of_stream       = " << s.end_of_stream << "\n"
    << "imu_samples         = " << s.imu_samples << "\n"
    << "imu_stale           = " << s.imu_stale << "\n"
    << "imu_stamp_anomaly   = " << s.imu_stamp_anomaly << "\n"
    << "frames              = " << s.frames << "\n"
    << "frames_incomplete   = " << s.frames_incomplete << "\n"
    << "frames_stale        = " << s.frames_stale << "\n"
    << "frames_inconsistent = " << s.frames_inconsistent << "\n";
}

StreamReceiver::StreamReceiver(const ReceiverParams& params) : params_(params) {
  if (params_.reorder_window == 0) params_.reorder_window = 1;
}

void StreamReceiver::push(const std::uint8_t* data, std::size_t n, SteadyClock::time_point now,
                          std::vector<StreamEvent>& out) {
  ++stats_.datagrams;
  stats_.bytes += n;
  Packet p;
  const DecodeError err = decode(data, n, p);
  if (err != DecodeError::None) {
    ++stats_.malformed;
    ++stats_.malformed_by_reason[static_cast<int>(err)];
    tick(now, out);
    return;
  }
  const std::uint64_t session = p.header.session;
  if (!session_ || session != *session_) {
    if (std::find(retired_sessions_.begin(), retired_sessions_.end(), session) !=
        retired_sessions_.end()) {
      ++stats_.stale_session;
      tick(now, out);
      return;
    }
    startSession(session, now, out);
  }
  const std::uint64_t seq = p.header.sequence;
  if (seq > next_seq_ && seq - next_seq_ >= kMaxSequenceJump) {
    // A valid CRC on a sequence number no sender reaches: treating it as real would count
    // billions of datagrams lost and give up every later one as late.
    ++stats_.malformed;
    ++stats_.malformed_by_reason[static_cast<int>(DecodeError::BadContent)];
    tick(now, out);
    return;
  }
  if (seq < next_seq_) {
    if (skipped_.erase(seq) > 0)
      ++stats_.late;
    else
      ++stats_.duplicates;
  } else if (held_.count(seq) > 0) {
    ++stats_.duplicates;
  } else {
    if (seq < max_seq_seen_) ++stats_.out_of_order;
    max_seq_seen_ = std::max(max_seq_seen_, seq);
    held_.emplace(seq, Held{std::move(p), now});
    releaseInOrder(out);
    while (held_.size() > params_.reorder_window) skipGap(out);
  }
  tick(now, out);
}

void StreamReceiver::tick(SteadyClock::time_point now, std::vector<StreamEvent>& out) {
  const auto timeout = std::chrono::duration<double>(params_.reorder_timeout);
  while (!held_.empty()) {
    auto oldest = held_.begin()->second.received;
    for (const auto& h : held_) oldest = std::min(oldest, h.second.received);
    if (now - oldest <= timeout) break;
    skipGap(out);
  }
  if (assembly_ &&
      now - assembly_->last_chunk > std::chrono::duration<double>(params_.frame_timeout))
    dropAssembly();
}

void StreamReceiver::startSession(std::uint64_t session, SteadyClock::time_point now,
                                  std::vector<StreamEvent>& out) {
  if (session_) {
    while (!held_.empty()) skipGap(out);  // what the old session still holds, in order
    dropAssembly();
    retired_sessions_.push_back(*session_);
    if (retired_sessions_.size() > kMaxRetiredSessions) retired_sessions_.pop_front();
  }
  session_ = session;
  next_seq_ = 0;
  max_seq_seen_ = 0;
  released_in_session_ = false;
  skipped_.clear();
  ++stats_.sessions;
  StreamEvent e;
  e.kind = StreamEvent::Kind::SessionStart;
  e.session = session;
  e.received = now;
  out.push_back(std::move(e));
}

void StreamReceiver::releaseInOrder(std::vector<StreamEvent>& out) {
  while (!held_.empty() && held_.begin()->first == next_seq_) {
    auto node = held_.extract(held_.begin());
    ++next_seq_;
    released_in_session_ = true;
    handle(node.mapped().packet, node.mapped().received, out);
  }
}

void StreamReceiver::skipGap(std::vector<StreamEvent>& out) {
  const std::uint64_t first = held_.begin()->first;
  if (!released_in_session_ && stats_.sessions == 1)
    stats_.joined_late += first - next_seq_;  // sent before we listened
  else
    stats_.lost += first - next_seq_;
  for (std::uint64_t s = next_seq_; s < first && skipped_.size() < kMaxSkippedRemembered; ++s)
    skipped_.insert(s);
  next_seq_ = first;
  releaseInOrder(out);
}

void StreamReceiver::handle(Packet& p, SteadyClock::time_point received,
                            std::vector<StreamEvent>& out) {
  switch (p.header.type) {
    case PacketType::Imu:
      for (const auto& s : p.imu) {
        if (last_imu_ns_ && s.stamp_ns <= *last_imu_ns_) {
          ++stats_.imu_stale;
          continue;
        }
        // A stamp ahead of the stream's clock is not adopted as its last one.
        if (!stampFitsClock(s.stamp_ns, received)) {
          ++stats_.imu_stamp_anomaly;
          continue;
        }
        last_imu_ns_ = s.stamp_ns;
        ++stats_.imu_samples;
        StreamEvent e;
        e.kind = StreamEvent::Kind::Imu;
        e.session = *session_;
        e.imu = s;
        e.received = received;
        out.push_back(std::move(e));
      }
      break;
    case PacketType::FrameChunk:
      handleChunk(p.chunk, received, out);
      break;
    case PacketType::EndOfStream: {
      ++stats_.end_of_stream;
      dropAssembly();
      StreamEvent e;
      e.kind = StreamEvent::Kind::EndOfStream;
      e.session = *session_;
      e.received = received;
      out.push_back(std::move(e));
      break;
    }
  }
}

bool StreamReceiver::stampFitsClock(std::int64_t stamp_ns, SteadyClock::time_point received) {
  const double stamp = static_cast<double>(stamp_ns) * 1e-9;
  const double offset = stamp - seconds(received);
  auto accept = [&] {
    clock_offsets_.push_back(offset);
    clock_stamps_.push_back(stamp);
    if (clock_offsets_.size() > kClockSamples) {
      clock_offsets_.pop_front();
      clock_stamps_.pop_front();
    }
    anomalous_since_.reset();
    return true;
  };
  const std::size_t n = clock_offsets_.size();
  if (n < kClockMinSamples) return accept();
  std::vector<double> v(clock_offsets_.begin(), clock_offsets_.end());
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(n / 2), v.end());
  const double interval =
      std::abs(clock_stamps_.back() - clock_stamps_.front()) / static_cast<double>(n - 1);
  if (std::abs(offset - v[n / 2]) <= std::max(kClockTolerance, 50.0 * interval)) return accept();
  if (!anomalous_since_) anomalous_since_ = received;
  if (seconds(received) - seconds(*anomalous_since_) > kClockStepAfter) {
    clock_offsets_.clear();  // the sender's clock stepped: a new model from here
    clock_stamps_.clear();
    return accept();
  }
  return false;
}

void StreamReceiver::handleChunk(FrameChunk& c, SteadyClock::time_point received,
                                 std::vector<StreamEvent>& out) {
  if (assembly_ && assembly_->frame.frame_id != c.frame_id) dropAssembly();  // superseded
  if (!assembly_) {
    Assembly a;
    a.frame.frame_id = c.frame_id;
    a.frame.stamp_ns = c.stamp_ns;
    a.frame.extrinsics = c.extrinsics;
    a.total_points = c.total_points;
    a.chunk_count = c.chunk_count;
    assembly_ = std::move(a);
  }
  Assembly& a = *assembly_;
  if (a.frame.stamp_ns != c.stamp_ns || a.total_points != c.total_points ||
      a.chunk_count != c.chunk_count || a.frame.extrinsics.R_bl != c.extrinsics.R_bl ||
      a.frame.extrinsics.p_bl != c.extrinsics.p_bl ||
      a.received_points + c.points.size() > a.total_points) {
    ++stats_.frames_inconsistent;
    assembly_.reset();
    return;
  }
  if (a.chunks.count(c.chunk_index) > 0) {
    ++stats_.duplicates;  // the same chunk again under a new sequence number
    return;
  }
  a.received_points += c.points.size();
  a.chunks.emplace(c.chunk_index, std::make_pair(c.first_point, std::move(c.points)));
  a.last_chunk = received;
  if (a.chunks.size() < a.chunk_count) return;

  // All chunks are here; they must tile the frame in index order (no overlap, no hole), or some
  // points were never sent.
  std::uint64_t next_point = 0;
  bool tiled = true;
  for (const auto& [index, chunk] : a.chunks) {
    tiled = tiled && chunk.first == next_point;
    next_point += chunk.second.size();
  }
  if (!tiled || next_point != a.total_points) {
    ++stats_.frames_inconsistent;
    assembly_.reset();
    return;
  }

  if (last_frame_ns_ && a.frame.stamp_ns <= *last_frame_ns_) {
    ++stats_.frames_stale;
  } else {
    last_frame_ns_ = a.frame.stamp_ns;
    ++stats_.frames;
    a.frame.points.reserve(a.total_points);
    for (auto& [index, chunk] : a.chunks)
      a.frame.points.insert(a.frame.points.end(), chunk.second.begin(), chunk.second.end());
    StreamEvent e;
    e.kind = StreamEvent::Kind::Frame;
    e.session = *session_;
    e.frame = std::move(a.frame);
    e.received = received;
    out.push_back(std::move(e));
  }
  assembly_.reset();
}

void StreamReceiver::dropAssembly() {
  if (assembly_) ++stats_.frames_incomplete;
  assembly_.reset();
}

}  // namespace freeinit::net
