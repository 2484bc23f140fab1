// Whether a file given on a command line is one the apps wrote (a result, a snapshot, a table, a
// seek index), recognised by its content, not its name: a user who gives `static_map.simplemap`,
// `static_map.ply`, `velocity.png` or `initial_state.ini` where a recording or a configuration
// goes gets one line saying what the file is and what to give instead. Kept apart from
// file_kind.h (what a recording or a configuration is) so that the two grow independently.
#pragma once

#include <optional>
#include <string>

namespace freeinit::app_support {

enum class OutputFileKind {
  SimpleMap,     ///< an MRPT simple map (static_map.simplemap)
  Ply,           ///< a PLY point cloud (ours: static_map.ply)
  Png,           ///< a PNG image (static_map.png, velocity.png, starts.png, ...)
  InitialState,  ///< initial_state.ini
  TruthErrors,   ///< errors_wrt_gt.ini
  StreamStats,   ///< stream_stats.ini of freeinit-online
  Velocities,    ///< velocimeter.csv
  Trajectory,    ///< trajectory_tum.txt
  StartTable,    ///< starts.csv or starts.md
  SeekIndex,     ///< <input>.freeinit.idx
  GroundTruth,   ///< <input>.truth.csv of freeinit-sim
};

/// What `path` is when its first 4 KiB show it is one of the outputs above (a gzip file is
/// looked at decompressed); nullopt for anything else, a file that cannot be read included.
std::optional<OutputFileKind> outputFileKind(const std::string& path);

/// "the initial state a freeinit run wrote (initial_state.ini)", ... (for messages).
std::string describe(OutputFileKind kind);

/// The one-line problem of giving `path` as `role` ("<input.rawlog>", "<config.ini>") when it
/// is one of the outputs above: "<role> 'path' is <what>, not <expected>: give <instead>"; ""
/// when it is none of them. `expected`: "a recording", "a configuration"; `instead`: what to
/// give ("the .rawlog the run read").
std::string outputGivenAsInput(const std::string& path, const std::string& role,
                               const std::string& expected, const std::string& instead);

}  // namespace freeinit::app_support
