// freeinit-online <config.ini> [--port N] [--out DIR]: Free-Init on a live Doppler LiDAR + IMU
// stream (docs/wire_format.md); writes initial_state.ini the moment the window closes.
#include <freeinit/mrpt_plugins/command_line.h>
#include <freeinit/mrpt_plugins/free_init_online_app.h>

#include <iostream>

int main(int argc, char** argv) {
  namespace plugins = freeinit::mrpt_plugins;
  namespace config = freeinit::config;
  plugins::CommandLine cli("freeinit-online",
                           "initial state from a live Doppler LiDAR + IMU UDP stream, written as "
                           "soon as the initialization window closes; the stream is recorded as a "
                           "rawlog");
  const auto& ini = cli.positional("config.ini", "INI configuration file (ini/freeinit.ini)");
  const auto& out = cli.text("o", "out", "output folder", "freeinit_online_out", "DIR");
  const auto& record =
      cli.text("r", "record", "recording file name in the output folder (\"\": none)",
               "live.rawlog", "FILE");
  const auto& address =
      cli.text("a", "address", "local IPv4 address to listen on", "127.0.0.1", "IP");
  const auto& port = cli.integer("p", "port", "UDP port (0: any free port)", 47800, 0, 65535, "N");
  const auto& wait = cli.number("w", "wait", "give up if no data for S s at start (0: wait)", 0,
                                config::between(0, 86400), "S");
  const auto& idle = cli.number("i", "idle-timeout", "end after S s without data", 2.0,
                                config::aboveUpTo(0, 86400), "S");
  const auto& max_duration = cli.number("d", "max-duration", "end after S s (0: no limit)", 0,
                                        config::between(0, 1e7), "S");
  const auto& stop_ready = cli.flag("", "stop-when-ready", "end as soon as the state is written");
  const auto& ignore_end =
      cli.flag("", "ignore-end-marker", "keep listening after the sender's end-of-stream marker");
  if (const auto code = cli.parse(argc, argv)) return *code;
  return plugins::runMain(cli.program(), [&] {
    plugins::FreeInitOnlineApp app;
    app.params.config_file = ini.value;
    app.params.out_dir = out.value;
    app.params.record = record.value;
    app.params.source.address = address.value;
    app.params.source.port = static_cast<std::uint16_t>(port.value);
    app.params.wait_first = wait.value;
    app.params.idle_timeout = idle.value;
    app.params.max_duration = max_duration.value;
    app.params.stop_when_ready = stop_ready.value;
    app.params.stop_at_end_of_stream = !ignore_end.value;
    return app.run(std::cout);
  });
}
