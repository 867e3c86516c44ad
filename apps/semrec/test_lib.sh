# Shared by the CLI test scripts (sourced).
fail() { echo "FAIL: $*"; exit 1; }
# Ends the test as skipped (exit 77: CTest's SKIP_RETURN_CODE), or as failed under
# SEMREC_REQUIRE_ALL=1 (set by .ci/run, where data, models and tools must all be present).
skip() {
  if [ "${SEMREC_REQUIRE_ALL:-0}" = 1 ]; then
    echo "FAIL: $* [a skip is a failure under SEMREC_REQUIRE_ALL=1]"; exit 1
  fi
  echo "SKIP: $*"; exit 77
}
