// Fuzz target: a lab curve CSV (header, columns, numbers, comments) through
// readCurveCsv and its validation.
#include <cstddef>
#include <cstdint>

#include "bridge/curve.hpp"
#include "bridge/errors.hpp"
#include "fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  gabion::bridge::CurveRequest request;
  request.x_name = "displacement_m";
  request.y_name = "force_N";
  try {
    (void)gabion::bridge::readCurveCsv(gabion::fuzz::inputFile(data, size, ".csv"), request);
  } catch (const gabion::bridge::InputError&) {
  }
  return 0;
}
