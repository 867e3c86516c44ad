// Scenes shared by the USD and GLB writer tests.
#pragma once

#include <cstdint>
#include <vector>

#include "semrec/usd/usda_writer.h"

namespace semrec::usd::test_scenes {

/// A person walking along +x at 0.5 m per frame, seen in `frames`; exactly
/// representable values, so written text is predictable.
inline PersonTrack Walker(uint32_t id, const std::vector<size_t>& frames) {
  PersonTrack p;
  p.track_id = id;
  for (size_t f : frames) {
    PersonSample s;
    s.frame = f;
    s.centroid_world = {0.5f * f, 1.0f, 1.0f};
    s.points_world = {{0.5f * f - 0.25f, 1.0f, 0.0f},
                      {0.5f * f + 0.25f, 1.125f, 2.0f}};
    p.samples.push_back(s);
  }
  return p;
}

}  // namespace semrec::usd::test_scenes
