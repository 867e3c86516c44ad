// The messages of a ROS 2 bag, whatever its storage: MCAP files (the default
// since ROS 2 Iron) or SQLite .db3 files (older rosbag2). Internal to the bag
// layout (io/layout_bag.cc) and `semrec info`.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace semrec::io::internal {

/// Where a message lies in its storage (opaque to the caller).
struct BagMessageRef {
  uint32_t file = 0;
  uint64_t a = 0, b = 0, c = 0;
};

struct BagMessage {
  const std::string* topic = nullptr;
  const std::string* type = nullptr;  // e.g. "sensor_msgs/msg/Image"
  int64_t log_time_ns = 0;
  const uint8_t* data = nullptr;
  size_t size = 0;
  BagMessageRef ref;
  /// How far the scan is, in units of Extent() (bytes of MCAP, messages of
  /// SQLite), for progress.
  uint64_t done = 0;
};

class BagStorage {
 public:
  virtual ~BagStorage() = default;
  /// Visits every message, in each file's order (files in bag order).
  virtual void Scan(const std::function<void(const BagMessage&)>& visit) = 0;
  /// What a whole Scan() goes through (see BagMessage::done).
  virtual uint64_t Extent() const = 0;
  /// One message's bytes again.
  virtual std::vector<uint8_t> Read(const BagMessageRef& ref) = 0;
  /// "mcap" or "sqlite3", and a line about the files (compression...).
  virtual std::string Storage() const = 0;
  virtual std::string Describe() const = 0;
  /// The file a ref lies in, for messages.
  virtual std::filesystem::path File(const BagMessageRef& ref) const = 0;
};

/// The bag at `path` (a .mcap or .db3 file, or a rosbag2 folder with
/// metadata.yaml, or a folder of .mcap files); nullptr when `path` is none
/// of these. Throws FormatError for a broken bag.
std::unique_ptr<BagStorage> OpenBag(const std::filesystem::path& path);

}  // namespace semrec::io::internal
