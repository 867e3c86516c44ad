// One libFuzzer binary per target (SEMREC_FUZZ_TARGET names it).
#include <cstddef>
#include <cstdint>

#include "fuzz/targets.h"

namespace {
const semrec::fuzz::Target* target = nullptr;
}  // namespace

extern "C" int LLVMFuzzerInitialize(int* /*argc*/, char*** /*argv*/) {
  target = &semrec::fuzz::FindTarget(SEMREC_FUZZ_TARGET);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  semrec::fuzz::RunOne(*target, data, size);
  return 0;
}
