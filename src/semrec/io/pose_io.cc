#include "semrec/io/pose_io.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>
#include <Eigen/SVD>
#include <nlohmann/json.hpp>

#include "semrec/core/error.h"
#include "semrec/core/file_util.h"
#include "semrec/io/json_file.h"

namespace fs = std::filesystem;

namespace semrec::io {
namespace {

// Numbers of a whitespace-separated text; throws FormatError naming the line of
// a bad token.
std::vector<std::vector<double>> ReadNumberRows(const fs::path& path) {
  std::istringstream in(ReadTextFile(path));
  std::vector<std::vector<double>> rows;
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    std::istringstream tokens(line);
    std::vector<double> row;
    std::string token;
    while (tokens >> token) {
      try {
        size_t used = 0;
        row.push_back(std::stod(token, &used));
        if (used != token.size()) throw std::invalid_argument(token);
      } catch (const std::exception&) {
        throw FormatError(path, fmt::format("line {}: '{}' is not a number",
                                            line_number, token));
      }
    }
    if (!row.empty()) rows.push_back(std::move(row));
  }
  return rows;
}

Transform MatrixFromRows(const fs::path& path,
                         const std::vector<std::vector<double>>& rows,
                         size_t first, const std::string& what) {
  Eigen::Matrix4d m;
  for (int r = 0; r < 4; ++r) {
    const auto& row = rows.at(first + r);
    if (row.size() != 4) {
      throw FormatError(
          path, fmt::format("{}: matrix row {} has {} numbers, expected 4",
                            what, r + 1, row.size()));
    }
    for (int c = 0; c < 4; ++c) m(r, c) = row[c];
  }
  try {
    return Transform::FromMatrix(m, what);
  } catch (const InvalidArgument& e) {
    throw FormatError(path, e.what());
  }
}

}  // namespace

std::vector<Transform> ReadRedwoodLog(const fs::path& path) {
  const auto rows = ReadNumberRows(path);
  if (rows.empty()) throw FormatError(path, "trajectory file is empty");
  if (rows.size() % 5 != 0) {
    throw FormatError(
        path,
        fmt::format("expected blocks of 5 lines (\"i j n\" + 4 matrix rows), "
                    "got {} non-empty lines: a pose has too few rows",
                    rows.size()));
  }
  std::vector<Transform> poses;
  for (size_t i = 0; i < rows.size(); i += 5) {
    if (rows[i].size() != 3) {
      throw FormatError(
          path,
          fmt::format("pose {}: header must be 3 numbers \"i j n\", got {}",
                      i / 5, rows[i].size()));
    }
    poses.push_back(
        MatrixFromRows(path, rows, i + 1, fmt::format("pose {}", i / 5)));
  }
  return poses;
}

Transform ReadPoseMatrixFile(const fs::path& path) {
  const auto rows = ReadNumberRows(path);
  if (rows.size() != 4) {
    throw FormatError(
        path,
        fmt::format("pose file must have 4 rows of 4 numbers, got {} rows",
                    rows.size()));
  }
  return MatrixFromRows(path, rows, 0, "pose");
}

std::vector<StampedPose> ReadTumTrajectory(const fs::path& path) {
  const auto rows = ReadNumberRows(path);
  std::vector<StampedPose> out;
  for (size_t i = 0; i < rows.size(); ++i) {
    const auto& r = rows[i];
    if (r.size() != 8) {
      throw FormatError(
          path,
          fmt::format("entry {}: expected 8 numbers \"timestamp tx ty tz qx qy "
                      "qz qw\", got {}",
                      i + 1, r.size()));
    }
    try {
      out.push_back({r[0], Transform::FromQuaternion(
                               Eigen::Quaterniond(r[7], r[4], r[5], r[6]),
                               Eigen::Vector3d(r[1], r[2], r[3]))});
    } catch (const InvalidArgument& e) {
      throw FormatError(path, fmt::format("entry {}: {}", i + 1, e.what()));
    }
  }
  if (out.empty()) throw FormatError(path, "trajectory file has no poses");
  std::stable_sort(out.begin(), out.end(),
                   [](const StampedPose& a, const StampedPose& b) {
                     return a.timestamp_s < b.timestamp_s;
                   });
  return out;
}

CameraIntrinsics ReadOpen3dIntrinsics(const fs::path& path) {
  const nlohmann::json j = ReadJsonFile(path);
  try {
    CameraIntrinsics k;
    k.width = j.at("width").get<int>();
    k.height = j.at("height").get<int>();
    const auto m = j.at("intrinsic_matrix").get<std::vector<double>>();
    if (m.size() != 9) {
      throw FormatError(path, "intrinsic_matrix must have 9 numbers");
    }
    // Column-major 3x3.
    k.fx = m[0];
    k.fy = m[4];
    k.cx = m[6];
    k.cy = m[7];
    k.Check();
    return k;
  } catch (const nlohmann::json::exception& e) {
    throw FormatError(
        path, std::string(
                  "expected {\"width\", \"height\", \"intrinsic_matrix\"}: ") +
                  e.what());
  } catch (const InvalidArgument& e) {
    throw FormatError(path, e.what());
  }
}

CameraIntrinsics ReadIntrinsicsMatrixFile(const fs::path& path, int width,
                                          int height) {
  const auto rows = ReadNumberRows(path);
  if (rows.size() != 3 || rows[0].size() != 3 || rows[1].size() != 3 ||
      rows[2].size() != 3) {
    throw FormatError(path, "expected a 3x3 matrix (3 rows of 3 numbers)");
  }
  CameraIntrinsics k{width,      height,     rows[0][0],
                     rows[1][1], rows[0][2], rows[1][2]};
  try {
    k.Check();
  } catch (const InvalidArgument& e) {
    throw FormatError(path, e.what());
  }
  return k;
}

void WriteRedwoodLog(const fs::path& path,
                     const std::vector<Transform>& poses) {
  std::string text;
  for (size_t i = 0; i < poses.size(); ++i) {
    text += fmt::format("{} {} {}\n", i, i, i + 1);
    const Eigen::Matrix4d m = poses[i].Matrix();
    for (int r = 0; r < 4; ++r) {
      text += fmt::format("{:.17g} {:.17g} {:.17g} {:.17g}\n", m(r, 0), m(r, 1),
                          m(r, 2), m(r, 3));
    }
  }
  WriteTextFileAtomic(path, text);
}

void WriteTumTrajectory(const fs::path& path,
                        const std::vector<StampedPose>& poses) {
  std::string text = "# timestamp tx ty tz qx qy qz qw\n";
  for (const StampedPose& p : poses) {
    const Eigen::Vector3d& t = p.T_world_camera.translation();
    const Eigen::Quaterniond q = p.T_world_camera.Quaternion();
    text += fmt::format(
        "{:.6f} {:.9g} {:.9g} {:.9g} {:.9g} {:.9g} {:.9g} {:.9g}\n",
        p.timestamp_s, t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w());
  }
  WriteTextFileAtomic(path, text);
}

namespace {

Eigen::Matrix4d MatrixFromYaml(const YAML::Node& node,
                               const std::filesystem::path& path,
                               const std::string& what, bool orthonormalize) {
  if (!node.IsSequence() || node.size() != 4) {
    throw FormatError(path, what + ": expected 4 rows of 4 numbers");
  }
  Eigen::Matrix4d m;
  for (int r = 0; r < 4; ++r) {
    if (!node[r].IsSequence() || node[r].size() != 4) {
      throw FormatError(
          path, fmt::format("{}: row {} must have 4 numbers", what, r + 1));
    }
    for (int c = 0; c < 4; ++c) {
      try {
        m(r, c) = node[r][c].as<double>();
      } catch (const YAML::Exception&) {
        throw FormatError(path, fmt::format("{}: row {} column {} is not a "
                                            "number",
                                            what, r + 1, c + 1));
      }
      if (!std::isfinite(m(r, c))) {
        throw FormatError(path, what + ": non-finite entry");
      }
    }
  }
  if (m.row(3) != Eigen::RowVector4d(0, 0, 0, 1)) {
    throw FormatError(path, what + ": the last row must be 0 0 0 1");
  }
  const Eigen::Matrix3d block = m.topLeftCorner<3, 3>();
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(
      block, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d R = svd.matrixU() * svd.matrixV().transpose();
  if (R.determinant() < 0) {
    throw FormatError(path, what +
                                ": the 3x3 block is a reflection, not a "
                                "rotation");
  }
  if (!orthonormalize && (R - block).cwiseAbs().maxCoeff() > 1e-3) {
    throw FormatError(path, what +
                                ": the 3x3 block is not a rotation (set "
                                "orthonormalize: true to use the nearest "
                                "one)");
  }
  m.topLeftCorner<3, 3>() = R;
  return m;
}

Eigen::Matrix4d ProductFromYaml(const YAML::Node& node,
                                const std::filesystem::path& path,
                                const std::string& key, bool orthonormalize) {
  if (!node) return Eigen::Matrix4d::Identity();
  // One matrix (rows of numbers) or a list of matrices.
  if (node.IsSequence() && node.size() > 0 && node[0].IsSequence() &&
      node[0].size() > 0 && node[0][0].IsSequence()) {
    Eigen::Matrix4d product = Eigen::Matrix4d::Identity();
    for (size_t k = 0; k < node.size(); ++k) {
      product =
          product * MatrixFromYaml(node[k], path, fmt::format("{}[{}]", key, k),
                                   orthonormalize);
    }
    return product;
  }
  return MatrixFromYaml(node, path, key, orthonormalize);
}

}  // namespace

Transform PoseCorrection::Apply(const Transform& T_file) const {
  const Eigen::Matrix4d m = pre * T_file.Matrix() * post;
  return Transform(m.topLeftCorner<3, 3>(), m.topRightCorner<3, 1>());
}

PoseCorrection ReadPoseCorrection(const std::filesystem::path& path) {
  RequireFile(path, "pose correction");
  YAML::Node root;
  try {
    root = YAML::LoadFile(path.string());
  } catch (const YAML::Exception& e) {
    throw FormatError(path, std::string("not valid YAML: ") + e.what());
  }
  if (!root.IsMap()) {
    throw FormatError(path, "expected a map with pre: and/or post:");
  }
  for (const auto& entry : root) {
    const std::string key = entry.first.as<std::string>();
    if (key != "pre" && key != "post" && key != "orthonormalize" &&
        key != "description") {
      throw FormatError(path, "unknown entry '" + key +
                                  "' (expected pre, post, orthonormalize, "
                                  "description)");
    }
  }
  bool orthonormalize = true;
  if (root["orthonormalize"]) {
    try {
      orthonormalize = root["orthonormalize"].as<bool>();
    } catch (const YAML::Exception&) {
      throw FormatError(path, "orthonormalize must be true or false");
    }
  }
  PoseCorrection c;
  c.pre = ProductFromYaml(root["pre"], path, "pre", orthonormalize);
  c.post = ProductFromYaml(root["post"], path, "post", orthonormalize);
  c.source = path.string();
  return c;
}

}  // namespace semrec::io
