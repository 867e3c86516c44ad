#include "arrays.h"

#include <cstring>

#include <nanobind/stl/string.h>

#include "semrec/detect/yolox_detector.h"

namespace semrec::python {

void Require(bool ok, bool type_error, const std::string& message) {
  if (ok) return;
  if (type_error) throw nb::type_error(message.c_str());
  throw nb::value_error(message.c_str());
}

std::string DescribeDtype(const AnyArray& a) {
  const nb::dlpack::dtype d = a.dtype();
  const char* kind = "?";
  switch (static_cast<nb::dlpack::dtype_code>(d.code)) {
    case nb::dlpack::dtype_code::Int:
      kind = "int";
      break;
    case nb::dlpack::dtype_code::UInt:
      kind = "uint";
      break;
    case nb::dlpack::dtype_code::Float:
      kind = "float";
      break;
    case nb::dlpack::dtype_code::Bool:
      return "bool";
    default:
      break;
  }
  return std::string(kind) + std::to_string(d.bits);
}

std::unique_ptr<infer::ModelRegistry> LoadRegistry(const std::string& name) {
  return std::make_unique<infer::ModelRegistry>(
      infer::ModelRegistry::LoadDefaultWith(name == "default" ? "" : name));
}

std::string DefaultDetector() { return detect::YoloxOptions().model; }

nb::object FromJson(const nlohmann::json& j) {
  return nb::module_::import_("json").attr("loads")(j.dump());
}

nb::ndarray<nb::numpy, double> MatrixToArray(const Eigen::MatrixXd& m) {
  const size_t rows = static_cast<size_t>(m.rows()),
               cols = static_cast<size_t>(m.cols());
  auto* data = new double[rows * cols];
  for (size_t r = 0; r < rows; ++r) {
    for (size_t c = 0; c < cols; ++c) {
      data[r * cols + c] =
          m(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c));
    }
  }
  nb::capsule owner(data,
                    [](void* p) noexcept { delete[] static_cast<double*>(p); });
  const size_t shape[2] = {rows, cols};
  return nb::ndarray<nb::numpy, double>(data, 2, shape, owner);
}

nb::ndarray<nb::numpy, uint32_t> TrianglesToArray(
    const std::vector<std::array<uint32_t, 3>>& triangles) {
  auto* data = new uint32_t[triangles.size() * 3 + 1];
  for (size_t i = 0; i < triangles.size(); ++i) {
    std::memcpy(data + 3 * i, triangles[i].data(), 3 * sizeof(uint32_t));
  }
  nb::capsule owner(
      data, [](void* p) noexcept { delete[] static_cast<uint32_t*>(p); });
  const size_t shape[2] = {triangles.size(), 3};
  return nb::ndarray<nb::numpy, uint32_t>(data, 2, shape, owner);
}

nb::dict MeshPrimDict(const usd::MeshPrim& p) {
  nb::dict d;
  d["id"] = p.instance_id;
  d["class"] = p.label;
  d["kind"] = p.structure ? "stuff" : "thing";
  d["vertices"] = PointsToArray(p.points);
  d["faces"] = TrianglesToArray(p.triangles);
  d["fused_points"] = p.point_count;
  d["confidence"] = p.confidence;
  d["first_seen_frame"] = p.first_seen_frame;
  d["last_seen_frame"] = p.last_seen_frame;
  return d;
}

nb::ndarray<nb::numpy, float> PointsToArray(
    const std::vector<Eigen::Vector3f>& points) {
  auto* data = new float[points.size() * 3 + 1];
  for (size_t i = 0; i < points.size(); ++i) {
    std::memcpy(data + 3 * i, points[i].data(), 3 * sizeof(float));
  }
  nb::capsule owner(data,
                    [](void* p) noexcept { delete[] static_cast<float*>(p); });
  const size_t shape[2] = {points.size(), 3};
  return nb::ndarray<nb::numpy, float>(data, 2, shape, owner);
}

}  // namespace semrec::python
