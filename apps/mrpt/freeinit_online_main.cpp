// freeinit-online <config.ini> [--port N] [--out DIR]: Free-Init on a live Doppler LiDAR + IMU
// stream (docs/wire_format.md); writes initial_state.ini the moment the window closes.
#include <freeinit/mrpt/FreeInitOnlineApp.h>
#include <mrpt/3rdparty/tclap/CmdLine.h>

#include <iostream>

int main(int argc, char** argv) {
  try {
    TCLAP::CmdLine cmd(
        "freeinit-online: initial state from a live Doppler LiDAR + IMU UDP stream, written as "
        "soon as the initialization window closes; the stream is recorded as a rawlog",
        ' ', "0.1");
    TCLAP::UnlabeledValueArg<std::string> ini("config", "INI configuration file", true, "",
                                              "config.ini", cmd);
    TCLAP::ValueArg<std::string> out("o", "out", "output folder", false, "freeinit_online_out",
                                     "DIR", cmd);
    TCLAP::ValueArg<std::string> record("r", "record",
                                        "recording file name in the output folder (\"\": none)",
                                        false, "live.rawlog", "FILE", cmd);
    TCLAP::ValueArg<std::string> address("a", "address", "local IPv4 address to listen on", false,
                                         "127.0.0.1", "IP", cmd);
    TCLAP::ValueArg<unsigned> port("p", "port", "UDP port", false, 47800, "N", cmd);
    TCLAP::ValueArg<double> wait("w", "wait", "give up if no data for S s at start (0: wait)",
                                 false, 0, "S", cmd);
    TCLAP::ValueArg<double> idle("i", "idle-timeout", "end after S s without data", false, 2.0, "S",
                                 cmd);
    TCLAP::ValueArg<double> max_duration("d", "max-duration", "end after S s (0: no limit)", false,
                                         0, "S", cmd);
    TCLAP::SwitchArg stop_ready("", "stop-when-ready", "end as soon as the state is written", cmd);
    TCLAP::SwitchArg ignore_end("", "ignore-end-marker",
                                "keep listening after the sender's end-of-stream marker", cmd);
    cmd.parse(argc, argv);
    if (port.getValue() > 65535) throw std::invalid_argument("--port must be in 0..65535");
    freeinit::mrpt_glue::FreeInitOnlineApp app;
    app.params.config_file = ini.getValue();
    app.params.out_dir = out.getValue();
    app.params.record = record.getValue();
    app.params.source.address = address.getValue();
    app.params.source.port = static_cast<std::uint16_t>(port.getValue());
    app.params.wait_first = wait.getValue();
    app.params.idle_timeout = idle.getValue();
    app.params.max_duration = max_duration.getValue();
    app.params.stop_when_ready = stop_ready.getValue();
    app.params.stop_at_end_of_stream = !ignore_end.getValue();
    return app.run(std::cout);
  } catch (const std::exception& e) {
    std::cerr << "freeinit-online: error: " << e.what() << "\n";
    return 1;
  }
}
