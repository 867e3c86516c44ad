// MOTChallenge text files: one box per line, "frame, id, left, top, width,
// height, conf, ...".
#pragma once

#include <filesystem>
#include <vector>

namespace semrec::io {

struct MotBox {
  int frame = 0;
  int id = 0;
  double left = 0.0;
  double top = 0.0;
  double width = 0.0;
  double height = 0.0;
  double confidence = 1.0;
};

/// Reads comma- or space-separated MOT lines (at least 6 numbers; the 7th is
/// the confidence, default 1). Throws FormatError naming the file and the line
/// for a wrong column count, a non-number, a non-integer frame or id, a frame <
/// 1, or a negative size. Empty files are fine. The result is sorted by (frame,
/// id); duplicates of (frame, id) are an error.
std::vector<MotBox> ReadMotFile(const std::filesystem::path& path);

/// Writes boxes as "frame,id,left,top,width,height,conf,-1,-1,-1", atomically.
void WriteMotFile(const std::filesystem::path& path,
                  const std::vector<MotBox>& boxes);

}  // namespace semrec::io
