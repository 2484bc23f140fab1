// The command line of every app, with one rule for all of them: --help, --version and
// --plugin-path (the MRPT plugin for stock tools, plugin_path.h) print and exit 0 doing nothing
// else; any unknown option, missing or extra argument, missing value,
// malformed or out-of-range value prints one line naming the flag and exits 2, doing nothing
// else; --help shows each option's default. Parsing is MRPT's bundled TCLAP (whose
// CmdLine::parse() returns false on --help, --version and errors instead of exiting); values are
// read by this class, strictly (a whole number must be one, "-1" is not an unsigned).
//
//   int main(int argc, char** argv) {
//     CommandLine cli("freeinit", "initial state from the first instants of a rawlog");
//     const auto& ini = cli.positional("config.ini", "INI configuration file");
//     const auto& out = cli.text("o", "out", "output folder", "freeinit_out", "DIR");
//     const auto& wait = cli.number("w", "wait", "give up after S s", 0, config::atLeast(0), "S");
//     if (const auto code = cli.parse(argc, argv)) return *code;
//     return runMain("freeinit", [&] { ...; return app.run(std::cout); });
//   }
#pragma once

#include <freeinit/io/config_section.h>

#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace freeinit::app_support {

/// The project's version, as --version prints it.
extern const char* const kVersion;

class CommandLine {
 public:
  /// A parsed value: the default until parse() reads the command line; `given` when it was on
  /// it.
  template <class T>
  struct Value {
    T value{};
    bool given = false;
  };

  CommandLine(std::string program, std::string description);
  ~CommandLine();
  CommandLine(const CommandLine&) = delete;
  CommandLine& operator=(const CommandLine&) = delete;

  /// A positional argument, in the order declared; `name` is its placeholder ("config.ini").
  /// The tokens go to the required positional arguments first; optional ones get the tokens
  /// beyond those, in the order declared (so an optional one may come first:
  /// `[<config.ini>] <input.rawlog>`).
  const Value<std::string>& positional(const std::string& name, const std::string& doc,
                                       bool required = true);
  /// The remaining positional arguments (declare it last).
  const Value<std::vector<std::string>>& positionals(const std::string& name,
                                                     const std::string& doc, bool required = true);

  // Options: `flag` is the one-letter form ("" for none), `name` the long form (--name).
  // `placeholder` names the value in the help ("DIR", "S"); `default_text`, when given, replaces
  // the default value in the help (e.g. "none" for an option that is off unless given).
  const Value<std::string>& text(const std::string& flag, const std::string& name,
                                 const std::string& doc, const std::string& default_value,
                                 const std::string& placeholder,
                                 const std::string& default_text = "");
  const Value<double>& number(const std::string& flag, const std::string& name,
                              const std::string& doc, double default_value, config::Range range,
                              const std::string& placeholder, const std::string& default_text = "");
  const Value<long long>& integer(const std::string& flag, const std::string& name,
                                  const std::string& doc, long long default_value, long long min,
                                  long long max, const std::string& placeholder,
                                  const std::string& default_text = "");
  /// A text option that must be given.
  const Value<std::string>& requiredText(const std::string& flag, const std::string& name,
                                         const std::string& doc, const std::string& placeholder);
  /// One of `choices`.
  const Value<std::string>& choice(const std::string& flag, const std::string& name,
                                   const std::string& doc, const std::string& default_value,
                                   const std::vector<std::string>& choices);
  /// A switch (no value).
  const Value<bool>& flag(const std::string& flag, const std::string& name, const std::string& doc);

  /// Parses the command line. nullopt: run the program. Otherwise the exit code to return at
  /// once: 0 after --help or --version (printed on stdout), 2 after a bad command line (one line
  /// on stderr naming the flag or argument, and how to get help).
  std::optional<int> parse(int argc, char** argv);

  /// A bad command line found after parse() (e.g. from the arguments' content): prints it as
  /// parse() does (one line naming it, and how to get help) and returns 2.
  int usageError(const std::string& what) const;

  /// What --help prints.
  std::string usage() const;
  const std::string& program() const { return program_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::string program_;
};

/// Runs a main's body: an exception becomes one line "<program>: error: <message>" on stderr
/// (the first line of the message: MRPT's exceptions carry a call stack) and exit code 1. The
/// stop handlers are installed first (stop_signal.h); a body that stops on a signal (Interrupted)
/// prints one line and the process ends by that signal.
int runMain(const std::string& program, const std::function<int()>& body);

}  // namespace freeinit::app_support
