// The [scenario] section of a scenario INI file: one declarative table of keys (name, unit,
// default, accepted range, one-line doc), the reader that applies a section over a base scenario,
// and the writer that writes every key a config uses, so that a written file read back gives the
// same config and therefore the same recording, bit for bit (numbers are written in their
// shortest exact form).
//
// A section is read over a base: `preset` names it (a preset name, or `random` for
// randomScenario(seed)), `seed` seeds it, every other key overrides the base's value. So the short
// form "preset = stat_01, seed = 7, duration = 0.5" and the complete form written by
// writeScenarioIni() are read by the same code. One rule is kept from the short form: giving b_g
// or b_a without random_biases turns random_biases off.
//
// MRPT-free: the caller reads the file (an INI reader gives key/value pairs); readScenarioIniText()
// is a minimal reader for callers without one.
#pragma once

#include <freeinit/sim/scenario.h>

#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace freeinit::sim {

/// One key of the [scenario] section.
struct ScenarioKey {
  std::string name;   ///< INI key; "object_<k>" stands for object_1, object_2, ...
  std::string unit;   ///< e.g. "s", "m/s", "deg"; "-" for pure numbers, "" for words
  std::string range;  ///< accepted values, e.g. "> 0", "[0, 1]", "street|corridor"
  std::string doc;    ///< one line
  /// The value as written (for object_<k>: the k-th object, k from 1).
  std::function<std::string(const ScenarioConfig&, int k)> format;
  /// Sets the value from its text; throws std::invalid_argument saying what is wrong.
  std::function<void(const std::string&, ScenarioConfig&, int k)> parse;
  /// "" when the config's value is acceptable, else what is wrong with it.
  std::function<std::string(const ScenarioConfig&, int k)> check;
  /// Whether the key matters for this config (the writer writes only those).
  std::function<bool(const ScenarioConfig&)> applies;
  bool indexed = false;  ///< object_<k>
};

/// The key table, in the order the writer writes it.
const std::vector<ScenarioKey>& scenarioKeys();

/// The table as text: one line per key with its unit, default (dyna_01's value), range and doc.
std::string scenarioKeysHelp();

/// Key/value pairs of a [scenario] section, in file order.
using ScenarioKeyValues = std::vector<std::pair<std::string, std::string>>;

/// The base used when a section has no `preset` or `seed` key.
struct ScenarioBase {
  std::string preset = "dyna_01";  ///< a preset name or "random"
  std::uint64_t seed = 1;
};

/// Applies a section over its base. Throws std::invalid_argument "<key>: <what is wrong>" for an
/// unknown key, a key given twice, a malformed or out-of-range value, or an inconsistent result.
ScenarioConfig scenarioFromKeys(const ScenarioKeyValues& section, const ScenarioBase& base = {});

/// The complete [scenario] section of a config: every key that applies to it, preceded by the
/// comment lines (written as "; line").
std::string scenarioIni(const ScenarioConfig& config,
                        const std::vector<std::string>& comments = {});

/// Writes scenarioIni() to path atomically; throws std::runtime_error on I/O failure.
void writeScenarioIni(const std::string& path, const ScenarioConfig& config,
                      const std::vector<std::string>& comments = {});

/// The [scenario] section's pairs of an INI text: "key = value" lines, ';' or '#' comment lines,
/// other sections ignored. Throws std::invalid_argument "line N: ..." for a malformed line.
ScenarioKeyValues readScenarioIniText(const std::string& text);

}  // namespace freeinit::sim
