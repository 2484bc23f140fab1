// The live stream without MRPT: wire format round trips, malformed datagrams, the receiver's
// handling of loss, duplication, reordering, restarts and timeouts, and UDP over loopback.
#include <freeinit/net/stream_receiver.h>
#include <freeinit/net/stream_sender.h>
#include <freeinit/net/stream_source.h>
#include <freeinit/net/udp_socket.h>
#include <freeinit/net/wire_format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <random>
#include <thread>

using namespace freeinit;
using namespace freeinit::net;

namespace {

constexpr std::int64_t kT0 = 1'700'000'000'000'000'000;  // [ns]

ImuMessage imu(int k) {
  ImuMessage s;
  s.stamp_ns = kT0 + k * 5'000'000LL;  // 200 Hz
  s.gyro = Vec3(0.1 * k, -0.2, 0.3 + 1e-9 * k);
  s.accel = Vec3(0.01, 9.81 - 1e-7 * k, -0.5);
  return s;
}

FrameMessage frame(int k, std::size_t n) {
  FrameMessage f;
  f.stamp_ns = kT0 + k * 100'000'000LL;  // 10 Hz
  f.extrinsics.R_bl = Eigen::AngleAxisd(0.3, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  f.extrinsics.p_bl = Vec3(0.1, -0.02, 0.05);
  std::mt19937 rng(static_cast<unsigned>(k));
  std::uniform_real_distribution<float> u(-50.f, 50.f);
  f.points.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    DopplerPoint& p = f.points[i];
    p.p_l = Eigen::Vector3f(u(rng), u(rng), u(rng));
    p.doppler = u(rng) / 10;
    p.time_offset = 0.1f * static_cast<float>(i) / static_cast<float>(n);
    p.intensity = u(rng) + 50;
    p.line = static_cast<std::uint16_t>(i % 64);
  }
  return f;
}

void expectSamePoints(const std::vector<DopplerPoint>& a, const std::vector<DopplerPoint>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].p_l, b[i].p_l) << i;
    ASSERT_EQ(a[i].doppler, b[i].doppler) << i;
    ASSERT_EQ(a[i].time_offset, b[i].time_offset) << i;
    ASSERT_EQ(a[i].intensity, b[i].intensity) << i;
    ASSERT_EQ(a[i].line, b[i].line) << i;
  }
}

// A stream of 20 IMU samples and 2 frames of 1000 points (several chunks each), as datagrams.
struct Stream {
  std::vector<std::vector<std::uint8_t>> datagrams;
  std::vector<ImuMessage> imu;
  std::vector<FrameMessage> frames;
};

Stream makeStream(std::uint64_t session, int first_imu = 0, int first_frame = 0) {
  Stream s;
  std::uint64_t seq = 0;
  for (int k = 0; k < 20; ++k) {
    s.imu.push_back(imu(first_imu + k));
    s.datagrams.push_back(encodeImu({s.imu.back()}, session, seq));
    if (k == 9 || k == 19) {
      s.frames.push_back(frame(first_frame + static_cast<int>(s.frames.size()), 1000));
      s.frames.back().frame_id = static_cast<std::uint32_t>(s.frames.size() - 1);
      for (auto& d : encodeFrame(s.frames.back(), session, seq, 8192)) s.datagrams.push_back(d);
    }
  }
  return s;
}

struct Output {
  std::vector<ImuMessage> imu;
  std::vector<FrameMessage> frames;
  int sessions = 0, ends = 0;
};

Output collect(const std::vector<StreamEvent>& events) {
  Output o;
  for (const auto& e : events) {
    switch (e.kind) {
      case StreamEvent::Kind::Imu:
        o.imu.push_back(e.imu);
        break;
      case StreamEvent::Kind::Frame:
        o.frames.push_back(e.frame);
        break;
      case StreamEvent::Kind::SessionStart:
        ++o.sessions;
        break;
      case StreamEvent::Kind::EndOfStream:
        ++o.ends;
        break;
    }
  }
  return o;
}

void push(StreamReceiver& r, const std::vector<std::uint8_t>& d, std::vector<StreamEvent>& out,
          SteadyClock::time_point t = SteadyClock::now()) {
  r.push(d.data(), d.size(), t, out);
}

}  // namespace

TEST(WireFormat, RoundTripIsExact) {
  std::uint64_t seq = 5;
  const auto d = encodeImu({imu(1), imu(2)}, 42, seq);
  EXPECT_EQ(seq, 6u);
  Packet p;
  ASSERT_EQ(decode(d.data(), d.size(), p), DecodeError::None);
  EXPECT_EQ(p.header.session, 42u);
  EXPECT_EQ(p.header.sequence, 5u);
  ASSERT_EQ(p.imu.size(), 2u);
  EXPECT_EQ(p.imu[1].stamp_ns, imu(2).stamp_ns);
  EXPECT_EQ(p.imu[1].gyro, imu(2).gyro);
  EXPECT_EQ(p.imu[1].accel, imu(2).accel);

  const FrameMessage f = frame(3, 1000);
  const auto chunks = encodeFrame(f, 42, seq, 1472);
  const std::size_t per = pointsPerChunk(1472);
  EXPECT_EQ(chunks.size(), (1000 + per - 1) / per);
  std::vector<DopplerPoint> points;
  for (const auto& c : chunks) {
    EXPECT_LE(c.size(), 1472u);
    ASSERT_EQ(decode(c.data(), c.size(), p), DecodeError::None);
    EXPECT_EQ(p.chunk.stamp_ns, f.stamp_ns);
    EXPECT_EQ(p.chunk.extrinsics.R_bl, f.extrinsics.R_bl);
    EXPECT_EQ(p.chunk.extrinsics.p_bl, f.extrinsics.p_bl);
    EXPECT_EQ(p.chunk.first_point, points.size());
    points.insert(points.end(), p.chunk.points.begin(), p.chunk.points.end());
  }
  expectSamePoints(points, f.points);
}

TEST(WireFormat, EveryCorruptionAndTruncationIsRejected) {
  std::uint64_t seq = 0;
  const auto chunks = encodeFrame(frame(0, 20), 7, seq, 8192);
  ASSERT_EQ(chunks.size(), 1u);
  const auto& good = chunks[0];
  Packet p;
  // Any single flipped byte: the CRC32 detects all burst errors up to 32 bits.
  for (std::size_t i = 0; i < good.size(); ++i) {
    auto bad = good;
    bad[i] ^= 0x5A;
    EXPECT_NE(decode(bad.data(), bad.size(), p), DecodeError::None) << "byte " << i;
  }
  for (std::size_t n = 0; n < good.size(); ++n)
    EXPECT_NE(decode(good.data(), n, p), DecodeError::None) << "length " << n;
  auto longer = good;
  longer.push_back(0);
  EXPECT_EQ(decode(longer.data(), longer.size(), p), DecodeError::BadLength);
  EXPECT_EQ(crc32(reinterpret_cast<const std::uint8_t*>("123456789"), 9), 0xCBF43926U);
}

TEST(WireFormat, StampsOutsideTheStreamRangeAreMalformed) {
  for (const std::int64_t stamp :
       {std::int64_t{-1}, kMaxStampNs, std::numeric_limits<std::int64_t>::min(),
        std::numeric_limits<std::int64_t>::max()}) {
    std::uint64_t seq = 0;
    ImuMessage s = imu(0);
    s.stamp_ns = stamp;
    Packet p;
    const auto d = encodeImu({s}, 1, seq);
    EXPECT_EQ(decode(d.data(), d.size(), p), DecodeError::BadContent) << stamp;
    FrameMessage f = frame(0, 10);
    f.stamp_ns = stamp;
    const auto c = encodeFrame(f, 1, seq, 8192);
    EXPECT_EQ(decode(c[0].data(), c[0].size(), p), DecodeError::BadContent) << stamp;
  }
  std::uint64_t seq = 0;
  ImuMessage s = imu(0);
  s.stamp_ns = kMaxStampNs - 1;
  Packet p;
  const auto d = encodeImu({s}, 1, seq);
  EXPECT_EQ(decode(d.data(), d.size(), p), DecodeError::None);
}

TEST(WireFormat, RejectsWhatItCannotCarry) {
  std::uint64_t seq = 0;
  EXPECT_THROW(encodeFrame(frame(0, 0), 1, seq, 8192), std::invalid_argument);
  EXPECT_THROW(encodeFrame(frame(0, 10), 1, seq, 100), std::invalid_argument);
  EXPECT_THROW(encodeImu({}, 1, seq), std::invalid_argument);
}

TEST(StreamReceiver, CleanStreamComesOutExactlyAndInOrder) {
  const Stream s = makeStream(11);
  StreamReceiver r;
  std::vector<StreamEvent> ev;
  for (const auto& d : s.datagrams) push(r, d, ev);
  const Output o = collect(ev);
  EXPECT_EQ(o.sessions, 1);
  ASSERT_EQ(o.imu.size(), s.imu.size());
  for (std::size_t i = 0; i < o.imu.size(); ++i) EXPECT_EQ(o.imu[i].stamp_ns, s.imu[i].stamp_ns);
  ASSERT_EQ(o.frames.size(), 2u);
  for (int k = 0; k < 2; ++k) expectSamePoints(o.frames[k].points, s.frames[k].points);
  EXPECT_EQ(r.stats().anomalies(), 0u);
  EXPECT_EQ(r.stats().frames, 2u);
  // A frame is emitted after the IMU samples that preceded it on the wire.
  EXPECT_EQ(ev[11].kind, StreamEvent::Kind::Frame);
}

TEST(StreamReceiver, DuplicatesAndReorderingAreUndone) {
  const Stream s = makeStream(11);
  std::vector<std::vector<std::uint8_t>> wire;
  std::mt19937 rng(3);
  // Duplicate every 5th datagram, then shuffle within blocks of 8 (less than the window).
  for (std::size_t i = 0; i < s.datagrams.size(); ++i) {
    wire.push_back(s.datagrams[i]);
    if (i % 5 == 0) wire.push_back(s.datagrams[i]);
  }
  for (std::size_t b = 0; b + 8 <= wire.size(); b += 8)
    std::shuffle(wire.begin() + static_cast<std::ptrdiff_t>(b),
                 wire.begin() + static_cast<std::ptrdiff_t>(b + 8), rng);
  StreamReceiver r;
  std::vector<StreamEvent> ev;
  for (const auto& d : wire) push(r, d, ev);
  const Output o = collect(ev);
  ASSERT_EQ(o.imu.size(), s.imu.size());
  for (std::size_t i = 0; i < o.imu.size(); ++i) EXPECT_EQ(o.imu[i].stamp_ns, s.imu[i].stamp_ns);
  ASSERT_EQ(o.frames.size(), 2u);
  expectSamePoints(o.frames[1].points, s.frames[1].points);
  EXPECT_EQ(r.stats().duplicates, (s.datagrams.size() + 4) / 5);
  EXPECT_GT(r.stats().out_of_order, 0u);
  EXPECT_EQ(r.stats().lost + r.stats().late + r.stats().frames_incomplete, 0u);
}

TEST(StreamReceiver, ALostChunkDropsItsFrameAndIsCounted) {
  const Stream s = makeStream(11);
  StreamReceiver r;
  std::vector<StreamEvent> ev;
  // Datagram 10 is the first chunk of frame 0 (10 IMU datagrams before it).
  for (std::size_t i = 0; i < s.datagrams.size(); ++i)
    if (i != 10) push(r, s.datagrams[i], ev);
  // The gap is given up after the reorder timeout.
  r.tick(SteadyClock::now() + std::chrono::seconds(1), ev);
  const Output o = collect(ev);
  EXPECT_EQ(o.imu.size(), s.imu.size());
  ASSERT_EQ(o.frames.size(), 1u);
  expectSamePoints(o.frames[0].points, s.frames[1].points);
  EXPECT_EQ(r.stats().lost, 1u);
  EXPECT_EQ(r.stats().frames_incomplete, 1u);
  // The datagram arriving after its gap was given up is late, not a duplicate.
  push(r, s.datagrams[10], ev);
  EXPECT_EQ(r.stats().late, 1u);
  EXPECT_EQ(r.stats().duplicates, 0u);
}

TEST(StreamReceiver, ChunksThatDoNotTileTheFrameDropIt) {
  Stream s = makeStream(11);
  // Datagrams 10..13 are frame 0's chunks of 308, 308, 308 and 76 points. Move the last one onto
  // points 0..75: every chunk arrives and the counts add up, but points 924..999 were never sent.
  std::vector<std::uint8_t>& d = s.datagrams[13];
  Packet p;
  ASSERT_EQ(decode(d.data(), d.size(), p), DecodeError::None);
  ASSERT_EQ(p.chunk.chunk_index, 3);
  ASSERT_EQ(p.chunk.first_point, 924u);
  for (int i = 0; i < 4; ++i) d[kHeaderBytes + 12 + i] = 0;  // first point index
  const std::uint32_t crc = crc32(d.data(), d.size() - kCrcBytes);
  for (int i = 0; i < 4; ++i)
    d[d.size() - kCrcBytes + i] = static_cast<std::uint8_t>(crc >> (8 * i));
  ASSERT_EQ(decode(d.data(), d.size(), p), DecodeError::None);

  StreamReceiver r;
  std::vector<StreamEvent> ev;
  for (const auto& datagram : s.datagrams) push(r, datagram, ev);
  const Output o = collect(ev);
  ASSERT_EQ(o.frames.size(), 1u);
  expectSamePoints(o.frames[0].points, s.frames[1].points);
  EXPECT_EQ(r.stats().frames_inconsistent, 1u);
  EXPECT_EQ(o.imu.size(), s.imu.size());
}

TEST(StreamReceiver, AWindowFullOfLaterDatagramsGivesUpTheGap) {
  const Stream s = makeStream(11);
  ReceiverParams params;
  params.reorder_window = 4;
  params.reorder_timeout = 1e6;  // only the window bound acts
  StreamReceiver r(params);
  std::vector<StreamEvent> ev;
  for (std::size_t i = 0; i < 9; ++i)
    if (i != 1) push(r, s.datagrams[i], ev);
  EXPECT_EQ(r.stats().lost, 1u);  // datagram 1
  EXPECT_EQ(collect(ev).imu.size(), 8u);
}

TEST(StreamReceiver, JoiningARunningStreamIsNotCountedAsLoss) {
  const Stream s = makeStream(11);
  StreamReceiver r;
  std::vector<StreamEvent> ev;
  for (std::size_t i = 5; i < s.datagrams.size(); ++i) push(r, s.datagrams[i], ev);
  r.tick(SteadyClock::now() + std::chrono::seconds(1), ev);
  EXPECT_EQ(r.stats().joined_late, 5u);
  EXPECT_EQ(r.stats().lost, 0u);
  EXPECT_EQ(collect(ev).imu.size(), s.imu.size() - 5);
  EXPECT_EQ(collect(ev).frames.size(), 2u);
}

TEST(StreamReceiver, ASequenceNumberFarAheadIsMalformedNotAGap) {
  const Stream s = makeStream(11);
  StreamReceiver r;
  std::vector<StreamEvent> ev;
  for (std::size_t i = 0; i < 5; ++i) push(r, s.datagrams[i], ev);
  std::uint64_t far = 5 + (std::uint64_t{1} << 32);  // valid CRC, impossible sequence number
  const auto bogus = encodeImu({imu(100)}, 11, far);
  push(r, bogus, ev);
  for (std::size_t i = 5; i < s.datagrams.size(); ++i) push(r, s.datagrams[i], ev);
  r.tick(SteadyClock::now() + std::chrono::seconds(1), ev);
  EXPECT_EQ(r.stats().malformed_by_reason[static_cast<int>(DecodeError::BadContent)], 1u);
  EXPECT_EQ(r.stats().lost, 0u);
  EXPECT_EQ(r.stats().late, 0u);
  EXPECT_EQ(collect(ev).imu.size(), s.imu.size());
  EXPECT_EQ(collect(ev).frames.size(), 2u);
}

TEST(StreamReceiver, SessionStartCarriesTheReceiptTimeGiven) {
  const Stream s = makeStream(11);
  StreamReceiver r;
  std::vector<StreamEvent> ev;
  const auto t = SteadyClock::time_point(std::chrono::seconds(12345));
  push(r, s.datagrams[0], ev, t);
  ASSERT_FALSE(ev.empty());
  EXPECT_EQ(ev.front().kind, StreamEvent::Kind::SessionStart);
  EXPECT_EQ(ev.front().received, t);
}

TEST(StreamReceiver, SenderRestartDropsThePartialFrameAndStaleData) {
  const Stream a = makeStream(1);
  const Stream b = makeStream(2, 100, 10);  // after the restart, later stamps
  StreamReceiver r;
  std::vector<StreamEvent> ev;
  for (std::size_t i = 0; i < 12; ++i) push(r, a.datagrams[i], ev);  // frame 0 half sent
  for (const auto& d : b.datagrams) push(r, d, ev);
  push(r, a.datagrams[12], ev);  // a late datagram of the old session
  const Output o = collect(ev);
  EXPECT_EQ(o.sessions, 2);
  EXPECT_EQ(r.stats().frames_incomplete, 1u);
  EXPECT_EQ(r.stats().stale_session, 1u);
  EXPECT_EQ(o.imu.size(), 10u + b.imu.size());
  EXPECT_EQ(o.frames.size(), 2u);

  // A restart whose stamps go back in time: nothing older than what was emitted comes out.
  const Stream c = makeStream(3);
  for (const auto& d : c.datagrams) push(r, d, ev);
  EXPECT_EQ(r.stats().imu_stale, c.imu.size());
  EXPECT_EQ(r.stats().frames_stale, 2u);
  EXPECT_EQ(collect(ev).imu.size(), o.imu.size());
}

// Live, one IMU packet stamped 10 days ahead (issue 44): a counted anomaly, not the stream's last
// stamp: every later sample comes out (none stale), so an estimator's window does not close at
// it. A clock that steps and stays is taken on after a second.
TEST(StreamReceiver, AStampFarAheadOfTheStreamsClockIsAnAnomalyNotItsEnd) {
  StreamReceiver r;
  std::vector<StreamEvent> ev;
  const SteadyClock::time_point t0 = SteadyClock::now();
  auto at = [&](int k) { return t0 + std::chrono::microseconds(5000 * k + 1200); };
  std::uint64_t seq = 0;
  for (int k = 0; k < 400; ++k) {
    ImuMessage s = imu(k);
    if (k == 150) s.stamp_ns += 864'000LL * 1'000'000'000LL;  // ten days ahead
    push(r, encodeImu({s}, 7, seq), ev, at(k));
  }
  const Output o = collect(ev);
  EXPECT_EQ(r.stats().imu_stamp_anomaly, 1u);
  EXPECT_EQ(r.stats().imu_stale, 0u);
  EXPECT_EQ(r.stats().anomalies(), 1u);
  ASSERT_EQ(o.imu.size(), 399u);
  EXPECT_EQ(o.imu.back().stamp_ns, imu(399).stamp_ns);

  // The sender's clock steps by 10 s and stays: after a second of anomalies, the stream again.
  std::size_t before = o.imu.size();
  for (int k = 400; k < 800; ++k) {
    ImuMessage s = imu(k);
    s.stamp_ns += 10'000'000'000LL;
    push(r, encodeImu({s}, 7, seq), ev, at(k));
  }
  const Output o2 = collect(ev);
  EXPECT_GT(o2.imu.size(), before + 150);
  EXPECT_EQ(o2.imu.back().stamp_ns, imu(799).stamp_ns + 10'000'000'000LL);
}

TEST(StreamReceiver, GarbageIsCountedByReason) {
  StreamReceiver r;
  std::vector<StreamEvent> ev;
  push(r, {1, 2, 3}, ev);
  std::uint64_t seq = 0;
  auto d = encodeImu({imu(0)}, 1, seq);
  d[4] = 99;  // version
  push(r, d, ev);
  d = encodeImu({imu(0)}, 1, seq);
  d.back() ^= 1;  // CRC
  push(r, d, ev);
  EXPECT_EQ(r.stats().malformed, 3u);
  EXPECT_EQ(r.stats().malformed_by_reason[static_cast<int>(DecodeError::TooShort)], 1u);
  EXPECT_EQ(r.stats().malformed_by_reason[static_cast<int>(DecodeError::BadVersion)], 1u);
  EXPECT_EQ(r.stats().malformed_by_reason[static_cast<int>(DecodeError::BadCrc)], 1u);
  EXPECT_TRUE(ev.empty());
}

namespace {

/// The samples and 500-point frames of imu(k) / frame(k, 500) that came out are exactly as sent.
void expectAsSent(const Output& o) {
  for (const auto& s : o.imu) {
    const int k = static_cast<int>((s.stamp_ns - kT0) / 5'000'000LL);
    ASSERT_EQ(s.gyro, imu(k).gyro);
  }
  for (const auto& f : o.frames) {
    const int k = static_cast<int>((f.stamp_ns - kT0) / 100'000'000LL);
    expectSamePoints(f.points, frame(k, 500).points);
  }
}

}  // namespace

TEST(UdpLoopback, FaultyStreamIsSurvivedAndCounted) {
  UdpSourceParams sp;
  sp.port = 0;  // ephemeral
  UdpStreamSource source(sp);
  source.start();
  ASSERT_GT(source.port(), 0);
  EXPECT_TRUE(udpPortInUse("127.0.0.1", source.port()));

  FaultParams faults;
  faults.drop = 0.05;
  faults.duplicate = 0.05;
  faults.reorder = 0.05;
  faults.corrupt = 0.05;
  StreamSender sender("127.0.0.1", source.port(), 1472, faults);
  const int n_imu = 400;
  for (int k = 0; k < n_imu; ++k) {
    sender.sendImu(imu(k));
    if (k % 20 == 19) sender.sendFrame(frame(k / 20, 500));
    if (k == 200) {
      sender.sendGarbage(10);
      sender.restart();
    }
  }
  sender.sendEndOfStream();

  std::vector<StreamEvent> ev;
  for (int i = 0; i < 200 && collect(ev).ends == 0; ++i) source.poll(ev, 0.05);
  const Output o = collect(ev);
  const SourceStats st = source.stats();
  ASSERT_EQ(o.ends, 1) << "end of stream not received";
  EXPECT_EQ(o.sessions, 2);
  const SenderStats& ss = sender.stats();
  EXPECT_GT(ss.dropped + ss.corrupted + ss.duplicated + ss.reordered, 0u);
  // Every corrupted or garbage datagram is caught; every duplicate is recognized.
  // (A corrupted datagram that was also duplicated is two malformed ones.)
  EXPECT_GE(st.receiver.malformed, ss.corrupted + ss.garbage);
  EXPECT_GE(st.receiver.malformed + st.receiver.duplicates,
            ss.corrupted + ss.garbage + ss.duplicated);
  // Stamps strictly increase; samples come out exactly as sent.
  for (std::size_t i = 1; i < o.imu.size(); ++i)
    ASSERT_GT(o.imu[i].stamp_ns, o.imu[i - 1].stamp_ns);
  expectAsSent(o);
  // Nothing vanished silently: IMU samples not delivered are covered by counted losses.
  EXPECT_GT(st.receiver.lost, 0u);
  EXPECT_LT(o.imu.size(), static_cast<std::size_t>(n_imu));
  EXPECT_EQ(st.queue_dropped_frames + st.queue_dropped_imu, 0u);
}

// Datagrams cut short (a broken link): each is refused as malformed, never read as a shorter
// message; what arrives whole comes out exactly as sent.
TEST(UdpLoopback, TruncatedDatagramsAreRefusedEachOne) {
  UdpSourceParams sp;
  sp.port = 0;
  UdpStreamSource source(sp);
  source.start();
  FaultParams faults;
  faults.truncate = 0.1;
  faults.seed = 7;
  StreamSender sender("127.0.0.1", source.port(), 1472, faults);
  const int n_imu = 400;
  for (int k = 0; k < n_imu; ++k) {
    sender.sendImu(imu(k));
    if (k % 20 == 19) sender.sendFrame(frame(k / 20, 500));
  }
  sender.sendEndOfStream();
  std::vector<StreamEvent> ev;
  for (int i = 0; i < 200 && collect(ev).ends == 0; ++i) source.poll(ev, 0.05);
  const Output o = collect(ev);
  ASSERT_EQ(o.ends, 1) << "end of stream not received";
  const SenderStats& ss = sender.stats();
  ASSERT_GT(ss.truncated, 10u);
  EXPECT_EQ(source.stats().receiver.malformed, ss.truncated);
  EXPECT_LT(o.imu.size(), static_cast<std::size_t>(n_imu));
  expectAsSent(o);
}

TEST(UdpLoopback, AnEmptyDatagramIsCountedAsMalformed) {
  UdpSourceParams sp;
  sp.port = 0;
  UdpStreamSource source(sp);
  source.start();
  UdpSocket socket;
  socket.connect("127.0.0.1", source.port());
  const std::uint8_t none = 0;
  ASSERT_TRUE(socket.send(&none, 0));
  const auto deadline = SteadyClock::now() + std::chrono::seconds(20);
  while (source.stats().receiver.datagrams < 1 && SteadyClock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  const SourceStats st = source.stats();
  EXPECT_EQ(st.receiver.datagrams, 1u);
  EXPECT_EQ(st.receiver.malformed_by_reason[static_cast<int>(DecodeError::TooShort)], 1u);
}

TEST(UdpLoopback, AConsumerTooSlowGetsCountedDropsNotAGap) {
  UdpSourceParams sp;
  sp.port = 0;
  sp.max_queued_imu = 50;
  sp.max_queued_frames = 2;
  UdpStreamSource source(sp);
  source.start();
  StreamSender sender("127.0.0.1", source.port());
  for (int k = 0; k < 300; ++k) {
    sender.sendImu(imu(k));
    if (k % 20 == 19) sender.sendFrame(frame(k / 20, 200));
  }
  sender.sendEndOfStream();
  // The consumer waits until the receiver thread has taken every datagram (not a fixed sleep: on
  // a loaded machine that may be too short), then drains.
  const std::uint64_t sent = sender.stats().datagrams;
  const auto deadline = SteadyClock::now() + std::chrono::seconds(20);
  while (source.stats().receiver.datagrams < sent && SteadyClock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  ASSERT_EQ(source.stats().receiver.datagrams, sent) << "datagrams not all received in 20 s";
  std::vector<StreamEvent> ev;
  for (int i = 0; i < 100 && collect(ev).ends == 0; ++i) source.poll(ev, 0.05);
  const Output o = collect(ev);
  const SourceStats st = source.stats();
  EXPECT_EQ(o.imu.size(), 50u);
  EXPECT_EQ(o.frames.size(), 2u);
  EXPECT_EQ(st.queue_dropped_imu, 250u);
  EXPECT_EQ(st.queue_dropped_frames, 13u);
  EXPECT_EQ(o.imu.size() + st.queue_dropped_imu + st.receiver.lost, 300u);
}
