// A ROS recording (a ROS 1 bag; an MCAP file, a rosbag2 folder or a .db3 of ROS 2) read straight
// in, wherever a rawlog is read: its messages go through the importer's reader and stream
// ([bag_import] of the app's INI; bags/recording_reader.h) and come out as the records
// freeinit-import-bag would have written (CObservationIMU, CObservationPointCloud with sensorPose
// = the extrinsics), so that the ingest path, its checks and the result are those of the imported
// rawlog, to the last digit.
//
// Reading costs the window, not the file: seeking to a start restarts the container's read at
// that log time (less reorder_window and 1 s for clouds logged after their stamp), which the
// MCAP chunk index, the .db3 timestamp index and the ROS 1 bag's index (chunk info and index
// records: the bag time of every message and its chunk) answer without reading what comes before;
// reading stops once the window is read.
#pragma once

#include <freeinit/app_support/app_config.h>
#include <freeinit/mrpt_plugins/rawlog_reader.h>

#include <memory>
#include <string>

namespace freeinit::app_support {

/// True for a path the ROS readers take (by content: ros2::identifyRecording).
bool isRosRecording(const std::string& path);

/// A reader of `path`: the rawlog reader for a rawlog, a RawlogReader over a RecordSource for a
/// ROS recording (a ROS 1 bag when built with FREEINIT_WITH_ROSBAG). For a recording, the
/// extrinsics written as the clouds' sensorPose are the INI's when it gives them (a difference of
/// more than 0.1 deg or 1 mm with /tf_static goes to `warnings`), else those of /tf_static;
/// neither: InputError naming the file.
std::unique_ptr<mrpt_plugins::RawlogReader> openInput(const std::string& path,
                                                      const AppConfig& config,
                                                      const mrpt_plugins::RawlogIndexPolicy& index,
                                                      std::vector<std::string>* warnings);

}  // namespace freeinit::app_support
