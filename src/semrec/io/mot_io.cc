#include "semrec/io/mot_io.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

#include <fmt/format.h>

#include "semrec/core/checked_cast.h"
#include "semrec/core/error.h"
#include "semrec/core/file_util.h"

namespace semrec::io {

std::vector<MotBox> ReadMotFile(const std::filesystem::path& path) {
  std::istringstream in(ReadTextFile(path));
  std::vector<MotBox> boxes;
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream tokens(line);
    std::vector<double> v;
    std::string token;
    while (tokens >> token) {
      try {
        size_t used = 0;
        v.push_back(std::stod(token, &used));
        if (used != token.size()) throw std::invalid_argument(token);
      } catch (const std::exception&) {
        throw FormatError(path, fmt::format("line {}: '{}' is not a number",
                                            line_number, token));
      }
    }
    if (v.empty()) continue;
    if (v.size() < 6) {
      throw FormatError(
          path,
          fmt::format("line {}: {} columns, expected at least 6 (frame, id, "
                      "left, top, width, height)",
                      line_number, v.size()));
    }
    const std::optional<int> frame = CheckedCast<int>(v[0]);
    const std::optional<int> id = CheckedCast<int>(v[1]);
    if (!frame || !id || *frame < 1) {
      throw FormatError(
          path,
          fmt::format("line {}: frame and id must be integers, frame >= 1",
                      line_number));
    }
    if (!(v[4] >= 0 && v[5] >= 0) ||
        !std::isfinite(v[2] + v[3] + v[4] + v[5])) {
      throw FormatError(path,
                        fmt::format("line {}: box size must be finite and >= 0",
                                    line_number));
    }
    boxes.push_back(
        {*frame, *id, v[2], v[3], v[4], v[5], v.size() > 6 ? v[6] : 1.0});
  }
  std::stable_sort(
      boxes.begin(), boxes.end(), [](const MotBox& a, const MotBox& b) {
        return a.frame != b.frame ? a.frame < b.frame : a.id < b.id;
      });
  for (size_t i = 1; i < boxes.size(); ++i) {
    if (boxes[i].frame == boxes[i - 1].frame &&
        boxes[i].id == boxes[i - 1].id && boxes[i].id >= 0) {
      throw FormatError(path, fmt::format("frame {}: id {} appears twice",
                                          boxes[i].frame, boxes[i].id));
    }
  }
  return boxes;
}

void WriteMotFile(const std::filesystem::path& path,
                  const std::vector<MotBox>& boxes) {
  std::string text;
  for (const MotBox& b : boxes) {
    text += fmt::format("{},{},{:.3f},{:.3f},{:.3f},{:.3f},{:.6g},-1,-1,-1\n",
                        b.frame, b.id, b.left, b.top, b.width, b.height,
                        b.confidence);
  }
  WriteTextFileAtomic(path, text);
}

}  // namespace semrec::io
