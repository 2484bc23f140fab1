// freeinit-stream: plays a simulator preset or a rawlog as a live Doppler LiDAR + IMU UDP stream.
#include <freeinit/mrpt/StreamApp.h>
#include <mrpt/3rdparty/tclap/CmdLine.h>

#include <iostream>

int main(int argc, char** argv) {
  try {
    TCLAP::CmdLine cmd(
        "freeinit-stream: plays a simulator preset or a rawlog as a live Doppler LiDAR + IMU "
        "stream (docs/wire_format.md) over UDP, in real time or faster, with optional faults",
        ' ', "0.1");
    TCLAP::ValueArg<std::string> rawlog("i", "rawlog", "rawlog to play (default: simulate)", false,
                                        "", "FILE", cmd);
    TCLAP::ValueArg<std::string> preset("P", "preset", "simulator preset", false, "dyna_01", "NAME",
                                        cmd);
    TCLAP::ValueArg<unsigned> seed("s", "seed", "simulator seed", false, 1, "N", cmd);
    TCLAP::ValueArg<double> duration("d", "duration", "simulated seconds (0: the preset's)", false,
                                     0, "S", cmd);
    TCLAP::ValueArg<int> points("n", "points-per-frame", "simulated points per frame", false, 0,
                                "N", cmd);
    TCLAP::ValueArg<std::string> address("a", "address", "destination IPv4 address", false,
                                         "127.0.0.1", "IP", cmd);
    TCLAP::ValueArg<unsigned> port("p", "port", "destination UDP port", false, 47800, "N", cmd);
    TCLAP::ValueArg<unsigned> mtu("m", "max-datagram", "bytes per datagram (1472 for Ethernet)",
                                  false, 8192, "B", cmd);
    TCLAP::ValueArg<double> speed("x", "speed", "playback speed factor (0: as fast as possible)",
                                  false, 1.0, "F", cmd);
    TCLAP::ValueArg<double> wait("w", "wait-listener",
                                 "wait up to S s for a listener on the local port", false, 0, "S",
                                 cmd);
    TCLAP::ValueArg<double> drop("", "drop", "probability a datagram is lost", false, 0, "P", cmd);
    TCLAP::ValueArg<double> dup("", "duplicate", "probability a datagram is sent twice", false, 0,
                                "P", cmd);
    TCLAP::ValueArg<double> reorder("", "reorder", "probability a datagram is sent late", false, 0,
                                    "P", cmd);
    TCLAP::ValueArg<double> corrupt("", "corrupt", "probability a byte is flipped", false, 0, "P",
                                    cmd);
    TCLAP::ValueArg<unsigned> fault_seed("", "fault-seed", "seed of the fault draws", false, 1, "N",
                                         cmd);
    TCLAP::ValueArg<double> restart("", "restart-at", "restart the sender S s into the stream",
                                    false, -1, "S", cmd);
    TCLAP::ValueArg<int> garbage("", "garbage", "N random non-packets half-way", false, 0, "N",
                                 cmd);
    TCLAP::SwitchArg no_end("", "no-end-marker", "do not send the end-of-stream marker", cmd);
    TCLAP::SwitchArg in_g("", "imu-accel-in-g",
                          "the rawlog's accelerations are in g (sent as m/s^2)", cmd);
    cmd.parse(argc, argv);
    if (port.getValue() == 0 || port.getValue() > 65535)
      throw std::invalid_argument("--port must be in 1..65535");
    freeinit::mrpt_glue::StreamApp app;
    auto& p = app.params;
    p.rawlog = rawlog.getValue();
    p.preset = preset.getValue();
    p.seed = seed.getValue();
    p.duration = duration.getValue();
    p.points_per_frame = points.getValue();
    p.address = address.getValue();
    p.port = static_cast<std::uint16_t>(port.getValue());
    p.max_datagram = mtu.getValue();
    p.speed = speed.getValue();
    p.wait_listener = wait.getValue();
    p.faults.drop = drop.getValue();
    p.faults.duplicate = dup.getValue();
    p.faults.reorder = reorder.getValue();
    p.faults.corrupt = corrupt.getValue();
    p.faults.seed = fault_seed.getValue();
    p.restart_at = restart.getValue();
    p.garbage = garbage.getValue();
    p.end_marker = !no_end.getValue();
    p.imu_accel_in_g = in_g.getValue();
    app.run(std::cout);
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "freeinit-stream: error: " << e.what() << "\n";
    return 1;
  }
}
