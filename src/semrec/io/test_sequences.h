// Test helper: writes small, valid sequences in each supported layout, which
// tests then break in one specific way.
#pragma once

#include <filesystem>

#include "semrec/core/camera.h"
#include "semrec/core/transform.h"

namespace semrec::io::testing {

/// 8x6 images; depth of frame i is a constant (1.0 + 0.1 i) m; colour of frame
/// i is (10 i, 20, 30).
constexpr int kWidth = 8;
constexpr int kHeight = 6;
CameraIntrinsics TestIntrinsics();
/// Camera i sits at x = 0.1 i, looking along +z.
Transform TestPose(int i);

void WriteRedwood(const std::filesystem::path& dir, int frames);
void WriteSevenScenes(const std::filesystem::path& dir, int frames);
void WriteTum(const std::filesystem::path& dir, int frames);
void WriteManifestSequence(const std::filesystem::path& dir, int frames);

}  // namespace semrec::io::testing
