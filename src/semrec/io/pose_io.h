// Camera trajectories and intrinsics in the formats of public RGB-D datasets.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "semrec/core/camera.h"
#include "semrec/core/transform.h"

namespace semrec::io {

/// Redwood / Open3D `.log` trajectory: per frame a line "i j n" and 4 rows of a
/// 4x4 camera-to-world matrix. Returns T_world_camera per entry, in file order.
std::vector<Transform> ReadRedwoodLog(const std::filesystem::path& path);

/// A 4x4 camera-to-world matrix as 4 rows of 4 numbers (7-Scenes / 3DMatch
/// `frame-*.pose.txt`).
Transform ReadPoseMatrixFile(const std::filesystem::path& path);

/// One TUM trajectory sample: "timestamp tx ty tz qx qy qz qw"
/// (camera-to-world).
struct StampedPose {
  double timestamp_s = 0.0;
  Transform T_world_camera;
};
/// TUM `groundtruth.txt` (comments with '#'), sorted by time.
std::vector<StampedPose> ReadTumTrajectory(const std::filesystem::path& path);

/// Writes a TUM trajectory (one "timestamp tx ty tz qx qy qz qw" line per
/// pose, camera-to-world) atomically; ReadTumTrajectory reads it back.
void WriteTumTrajectory(const std::filesystem::path& path,
                        const std::vector<StampedPose>& poses);

/// Open3D PinholeCameraIntrinsic JSON ({"width", "height", "intrinsic_matrix":
/// 9 numbers, column-major}).
CameraIntrinsics ReadOpen3dIntrinsics(const std::filesystem::path& path);

/// A 3x3 K matrix as text (7-Scenes / 3DMatch `camera-intrinsics.txt`); the
/// image size is not in the file and is given by the caller.
CameraIntrinsics ReadIntrinsicsMatrixFile(const std::filesystem::path& path,
                                          int width, int height);

/// Writes a Redwood `.log` trajectory atomically.
/// A correction of a dataset's poses: T_world_camera = pre * T_file * post
/// (e.g. a motion-capture rig's pose -> the camera's, or a change of axes).
struct PoseCorrection {
  Eigen::Matrix4d pre = Eigen::Matrix4d::Identity();
  Eigen::Matrix4d post = Eigen::Matrix4d::Identity();
  /// Where it came from, for reports.
  std::string source;
  Transform Apply(const Transform& T_file) const;
};

/// Reads a pose correction (YAML): `pre:` and `post:`, each a 4x4 matrix
/// (4 rows of 4 numbers) or a list of such matrices multiplied left to right;
/// either may be missing (identity). Each matrix's 3x3 block is replaced by
/// the nearest rotation (a correction measured with a small scale error stays
/// rigid); `orthonormalize: false` refuses such matrices instead. Throws
/// FormatError naming the file and the entry for anything else.
PoseCorrection ReadPoseCorrection(const std::filesystem::path& path);

void WriteRedwoodLog(const std::filesystem::path& path,
                     const std::vector<Transform>& poses);

}  // namespace semrec::io
