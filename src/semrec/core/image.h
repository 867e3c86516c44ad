// Dense row-major images with interleaved channels.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "semrec/core/error.h"

namespace semrec {

/// A width x height image with `channels` interleaved values of type T per
/// pixel.
template <typename T>
class Image {
 public:
  using ValueType = T;

  Image() = default;
  Image(int width, int height, int channels = 1, T fill = T{})
      : width_(width), height_(height), channels_(channels) {
    CheckArgument(width >= 0 && height >= 0 && channels > 0,
                  "Image: width and height must be >= 0 and channels > 0");
    data_.assign(static_cast<size_t>(width) * height * channels, fill);
  }

  int width() const { return width_; }
  int height() const { return height_; }
  int channels() const { return channels_; }
  bool empty() const { return data_.empty(); }
  size_t NumPixels() const { return static_cast<size_t>(width_) * height_; }

  T& operator()(int x, int y, int c = 0) { return data_[Index(x, y, c)]; }
  const T& operator()(int x, int y, int c = 0) const {
    return data_[Index(x, y, c)];
  }

  T* data() { return data_.data(); }
  const T* data() const { return data_.data(); }
  std::vector<T>& values() { return data_; }
  const std::vector<T>& values() const { return data_; }

  bool SameSize(int width, int height) const {
    return width_ == width && height_ == height;
  }
  template <typename U>
  bool SameSize(const Image<U>& other) const {
    return SameSize(other.width(), other.height());
  }

  bool operator==(const Image& other) const = default;

 private:
  size_t Index(int x, int y, int c) const {
    return (static_cast<size_t>(y) * width_ + x) * channels_ + c;
  }

  int width_ = 0;
  int height_ = 0;
  int channels_ = 1;
  std::vector<T> data_;
};

/// 8-bit RGB colour image (3 channels, R first).
using ColorImage = Image<uint8_t>;
/// Raw 16-bit depth as stored in PNG files (units given by a depth scale).
using DepthImage16 = Image<uint16_t>;
/// Metric depth in metres; 0 marks an invalid pixel.
using DepthImage = Image<float>;

/// Converts raw 16-bit depth to metres: d_m = raw / depth_scale. Raw values
/// equal to 0 or to `invalid_value` become 0 (invalid), as do depths >=
/// max_depth_m (when max_depth_m > 0).
DepthImage DepthToMeters(const DepthImage16& raw, double depth_scale,
                         uint16_t invalid_value = 0, double max_depth_m = 0.0);

}  // namespace semrec
