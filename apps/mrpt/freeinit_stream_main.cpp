// freeinit-stream: plays a simulator preset or a rawlog as a live Doppler LiDAR + IMU UDP stream.
#include <freeinit/mrpt_plugins/command_line.h>
#include <freeinit/mrpt_plugins/stream_app.h>
#include <freeinit/net/wire_format.h>
#include <freeinit/sim/simulator.h>

#include <iostream>

int main(int argc, char** argv) {
  namespace plugins = freeinit::mrpt_plugins;
  namespace config = freeinit::config;
  using config::between;
  plugins::CommandLine cli("freeinit-stream",
                           "plays a simulator preset or a rawlog as a live Doppler LiDAR + IMU "
                           "stream (docs/wire_format.md) over UDP, in real time or faster, with "
                           "optional faults");
  const auto& rawlog = cli.text("i", "rawlog", "rawlog to play", "", "FILE", "none: simulate");
  const auto& preset =
      cli.choice("P", "preset", "simulator preset", "dyna_01", freeinit::sim::presetNames());
  const auto& seed = cli.integer("s", "seed", "simulator seed", 1, 0, 4294967295LL, "N");
  const auto& duration =
      cli.number("d", "duration", "simulated seconds (0: the preset's)", 0, between(0, 3600), "S");
  const auto& points = cli.integer(
      "n", "points-per-frame", "simulated points per frame (0: the preset's)", 0, 0, 10000000, "N");
  const auto& address = cli.text("a", "address", "destination IPv4 address", "127.0.0.1", "IP");
  const auto& port = cli.integer("p", "port", "destination UDP port", 47800, 1, 65535, "N");
  const auto& mtu = cli.integer("m", "max-datagram", "bytes per datagram (1472 for Ethernet)", 8192,
                                static_cast<long long>(freeinit::net::kMinDatagram),
                                static_cast<long long>(freeinit::net::kMaxDatagram), "B");
  const auto& speed = cli.number("x", "speed", "playback speed factor (0: as fast as possible)",
                                 1.0, between(0, 1000), "F");
  const auto& wait =
      cli.number("w", "wait-listener", "wait up to S s for a listener on the local port", 0,
                 between(0, 3600), "S");
  const auto& drop =
      cli.number("", "drop", "probability a datagram is lost", 0, between(0, 1), "P");
  const auto& dup =
      cli.number("", "duplicate", "probability a datagram is sent twice", 0, between(0, 1), "P");
  const auto& reorder =
      cli.number("", "reorder", "probability a datagram is sent late", 0, between(0, 1), "P");
  const auto& corrupt =
      cli.number("", "corrupt", "probability a byte is flipped", 0, between(0, 1), "P");
  const auto& fault_seed =
      cli.integer("", "fault-seed", "seed of the fault draws", 1, 0, 4294967295LL, "N");
  const auto& restart = cli.number("", "restart-at", "restart the sender S s into the stream", -1,
                                   between(0, 1e6), "S", "none");
  const auto& garbage =
      cli.integer("", "garbage", "N random non-packets half-way", 0, 0, 1000000, "N");
  const auto& no_end = cli.flag("", "no-end-marker", "do not send the end-of-stream marker");
  const auto& in_g =
      cli.flag("", "imu-accel-in-g", "the rawlog's accelerations are in g (sent as m/s^2)");
  if (const auto code = cli.parse(argc, argv)) return *code;
  return plugins::runMain(cli.program(), [&] {
    plugins::StreamApp app;
    auto& p = app.params;
    p.rawlog = rawlog.value;
    p.preset = preset.value;
    p.seed = static_cast<std::uint64_t>(seed.value);
    p.duration = duration.value;
    p.points_per_frame = static_cast<int>(points.value);
    p.address = address.value;
    p.port = static_cast<std::uint16_t>(port.value);
    p.max_datagram = static_cast<std::size_t>(mtu.value);
    p.speed = speed.value;
    p.wait_listener = wait.value;
    p.faults.drop = drop.value;
    p.faults.duplicate = dup.value;
    p.faults.reorder = reorder.value;
    p.faults.corrupt = corrupt.value;
    p.faults.seed = static_cast<std::uint64_t>(fault_seed.value);
    p.restart_at = restart.value;
    p.garbage = static_cast<int>(garbage.value);
    p.end_marker = !no_end.value;
    p.imu_accel_in_g = in_g.value;
    app.run(std::cout);
    return 0;
  });
}
