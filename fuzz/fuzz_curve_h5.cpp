// Fuzz target: an HDF5 file through the readers of lab curves and wall
// series (a run's result.h5 given as lab data) and the generic reader.
#include <cstddef>
#include <cstdint>

#include "bridge/curve.hpp"
#include "bridge/errors.hpp"
#include "bridge/output.hpp"
#include "fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto file = gabion::fuzz::inputFile(data, size, ".h5");
  try {
    gabion::bridge::CurveRequest request;
    (void)gabion::bridge::readCurveH5(file, "/curves/uc/displacement_m", "/curves/uc/force_N", request);
  } catch (const gabion::bridge::InputError&) {
  }
  try {
    for (const auto& wall : gabion::bridge::wallNamesH5(file)) (void)gabion::bridge::readWallSeriesH5(file, wall);
  } catch (const gabion::bridge::InputError&) {
  }
  return 0;
}
