// The [scenario] section of a scenario INI file, declared once as a config::Section (name, unit,
// default, accepted range, one-line doc of every key: `freeinit-sim --scenario-keys`), read with
// the project's INI reader (config::IniFile: unknown sections and keys, keys given twice,
// malformed and out-of-range values are errors naming the file, the line and the key), and
// written with every key a config uses, so that a written file read back gives the same config
// and therefore the same recording, bit for bit (numbers are written in their shortest exact
// form).
//
// A section is read over a base: `preset` names it (a preset name, or `random` for
// randomScenario(seed)), `seed` seeds it, every other key overrides the base's value. So the short
// form "preset = stat_01, seed = 7, duration = 0.5" and the complete form written by
// writeScenarioIni() are read by the same code. One rule is kept from the short form: giving b_g
// or b_a without random_biases turns random_biases off. Explicitly placed objects are the keys
// object_1 ... object_N, N the key `objects`.
//
// MRPT-free.
#pragma once

#include <freeinit/io/config_section.h>
#include <freeinit/io/ini_file.h>
#include <freeinit/sim/scenario.h>

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace freeinit::sim {

/// The declaration of [scenario]: every key, in the order the writer writes them.
const config::Section<ScenarioConfig>& scenarioSection();

/// The keys as text: one line per key with its unit, default (dyna_01's value), accepted values
/// and doc.
std::string scenarioKeysHelp();

/// The base used when a section has no `preset` or `seed` key.
struct ScenarioBase {
  std::string preset = "dyna_01";  ///< a preset name or "random"
  std::uint64_t seed = 1;
};

/// The [scenario] section of an INI file (its only section) over its base. Throws
/// config::ConfigError (a std::invalid_argument) "file:line: [scenario] key: what is wrong".
ScenarioConfig scenarioFromIni(const config::IniFile& ini, const ScenarioBase& base = {});

/// Reads the file (config::IniFile::load) and then scenarioFromIni().
ScenarioConfig loadScenarioIni(const std::string& path, const ScenarioBase& base = {});

/// Key/value pairs of a [scenario] section built in code.
using ScenarioKeyValues = std::vector<std::pair<std::string, std::string>>;

/// The same from pairs built in code; messages name "scenario keys" instead of a file.
ScenarioConfig scenarioFromKeys(const ScenarioKeyValues& section, const ScenarioBase& base = {});

/// The complete [scenario] section of a config: every key that applies to it, each with its unit,
/// doc and accepted values as a comment, preceded by the comment lines (written as "; line").
std::string scenarioIni(const ScenarioConfig& config,
                        const std::vector<std::string>& comments = {});

/// Writes scenarioIni() to path atomically; throws std::runtime_error on I/O failure.
void writeScenarioIni(const std::string& path, const ScenarioConfig& config,
                      const std::vector<std::string>& comments = {});

}  // namespace freeinit::sim
