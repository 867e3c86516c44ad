// numpy <-> semrec images for the Python module: checked conversions in (a
// clear TypeError / ValueError naming the argument for a wrong dtype, shape or
// layout) and zero-copy arrays out (the image moves into the array's owner);
// JSON out as Python objects; the helpers the module's parts share.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "semrec/core/image.h"
#include "semrec/infer/model_registry.h"
#include "semrec/usd/usda_writer.h"

namespace semrec::python {

namespace nb = nanobind;

/// Any numpy array (dtype and shape checked by the functions below).
using AnyArray = nb::ndarray<nb::numpy, nb::ro>;

/// Raises TypeError / ValueError (through nb::type_error / nb::value_error).
void Require(bool ok, bool type_error, const std::string& message);

template <typename T>
const char* DtypeName();
template <>
inline const char* DtypeName<uint8_t>() {
  return "uint8";
}
template <>
inline const char* DtypeName<uint16_t>() {
  return "uint16";
}
template <>
inline const char* DtypeName<float>() {
  return "float32";
}
template <>
inline const char* DtypeName<double>() {
  return "float64";
}

/// The array's dtype as numpy names it (for messages).
std::string DescribeDtype(const AnyArray& a);

/// Checks `a` is a C-contiguous `T` array of `ndim` dimensions (`channels` > 0:
/// the last one has that size).
template <typename T>
void CheckArray(const AnyArray& a, const char* name, size_t ndim,
                int channels = 0) {
  Require(a.dtype() == nb::dtype<T>(), true,
          std::string(name) + ": expected dtype " + DtypeName<T>() + ", got " +
              DescribeDtype(a));
  Require(a.ndim() == ndim, false,
          std::string(name) + ": expected " + std::to_string(ndim) +
              " dimensions, got " + std::to_string(a.ndim()));
  if (channels > 0) {
    Require(a.shape(ndim - 1) == static_cast<size_t>(channels), false,
            std::string(name) + ": expected " + std::to_string(channels) +
                " channels in the last dimension, got " +
                std::to_string(a.shape(ndim - 1)));
  }
  // C order: each stride (in elements) is the product of the later sizes.
  int64_t expected = 1;
  for (size_t d = ndim; d-- > 0;) {
    Require(
        a.shape(d) <= 1 || a.stride(d) == expected, false,
        std::string(name) +
            ": the array must be C-contiguous (use numpy.ascontiguousarray)");
    expected *= static_cast<int64_t>(a.shape(d));
  }
}

/// An H x W (x C) array as an image (copied).
template <typename T>
Image<T> ToImage(const AnyArray& a, const char* name, int channels) {
  CheckArray<T>(a, name, channels > 1 ? 3 : 2, channels > 1 ? channels : 0);
  const int h = static_cast<int>(a.shape(0)), w = static_cast<int>(a.shape(1));
  Require(h > 0 && w > 0, false, std::string(name) + ": the image is empty");
  Image<T> image(w, h, channels);
  const T* src = static_cast<const T*>(a.data());
  std::copy(src, src + image.values().size(), image.data());
  return image;
}

/// An image as a numpy array (H x W, or H x W x C when C > 1) without copying.
template <typename T>
nb::ndarray<nb::numpy, T> ToArray(Image<T> image) {
  auto* owned = new Image<T>(std::move(image));
  nb::capsule owner(owned,
                    [](void* p) noexcept { delete static_cast<Image<T>*>(p); });
  const size_t h = static_cast<size_t>(owned->height()),
               w = static_cast<size_t>(owned->width()),
               c = static_cast<size_t>(owned->channels());
  if (c == 1) {
    const size_t shape[2] = {h, w};
    return nb::ndarray<nb::numpy, T>(owned->data(), 2, shape, owner);
  }
  const size_t shape[3] = {h, w, c};
  return nb::ndarray<nb::numpy, T>(owned->data(), 3, shape, owner);
}

/// A rows x cols float64 matrix (copied).
template <int Rows, int Cols>
Eigen::Matrix<double, Rows, Cols> ToMatrix(const AnyArray& a,
                                           const char* name) {
  Require(a.dtype() == nb::dtype<double>() || a.dtype() == nb::dtype<float>(),
          true,
          std::string(name) + ": expected a float64 (or float32) array, got " +
              DescribeDtype(a));
  Require(a.ndim() == 2 && a.shape(0) == Rows && a.shape(1) == Cols, false,
          std::string(name) + ": expected shape (" + std::to_string(Rows) +
              ", " + std::to_string(Cols) + ")");
  Eigen::Matrix<double, Rows, Cols> m;
  const bool is_double = a.dtype() == nb::dtype<double>();
  for (int r = 0; r < Rows; ++r) {
    for (int c = 0; c < Cols; ++c) {
      const int64_t at = r * a.stride(0) + c * a.stride(1);
      m(r, c) = is_double ? static_cast<const double*>(a.data())[at]
                          : static_cast<const float*>(a.data())[at];
    }
  }
  return m;
}

/// A matrix as a new float64 numpy array.
nb::ndarray<nb::numpy, double> MatrixToArray(const Eigen::MatrixXd& m);

/// A JSON value as Python objects (through Python's json module: small
/// documents only).
nb::object FromJson(const nlohmann::json& j);

/// The installed registry (data/models.yaml), with a registry file's entries
/// merged over it unless `name` is "default".
std::unique_ptr<infer::ModelRegistry> LoadRegistry(const std::string& name);

/// The object detector `semrec run` and `semrec segment` use by default.
std::string DefaultDetector();

/// The module's parts defined in analysis.cc.
void BindSegmenter(nb::module_& m);
void BindEval(nb::module_& m);
void BindLoad(nb::module_& m);

/// M x 3 uint32 triangle vertex indices (copied).
nb::ndarray<nb::numpy, uint32_t> TrianglesToArray(
    const std::vector<std::array<uint32_t, 3>>& triangles);

/// A mesh prim as a dict: id, class, kind ("stuff"/"thing"), vertices,
/// faces, fused_points, confidence, first/last seen frame.
nb::dict MeshPrimDict(const usd::MeshPrim& p);

/// N x 3 float32 points (copied).
nb::ndarray<nb::numpy, float> PointsToArray(
    const std::vector<Eigen::Vector3f>& points);

}  // namespace semrec::python
