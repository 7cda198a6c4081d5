#include "micro/cases.hpp"

#include <utility>

#include "micro/cell/cell_assembly.hpp"
#include "micro/engine.hpp"
#include "micro/lab/compression_test.hpp"
#include "micro/lab/impact_test.hpp"
#include "micro/lab/shear_test.hpp"
#include "micro/lab/structure_impact.hpp"
#include "micro/netting/tensile_test.hpp"
#include "micro/scene.hpp"
#include "micro/scene_run.hpp"

namespace gabion::micro {
namespace {

void checkScene(const bridge::JsonDocument& doc) {
  const Scene scene = parseScene(doc.root());
  chooseDt(scene, criticalTimeStep(scene), doc.file());
}

bridge::RunOutcome runSceneCase(const bridge::JsonDocument& doc, const bridge::RunContext& ctx) {
  Scene scene = parseScene(doc.root());
  // Everything is read: a large case's DOM need not stay beside the engine.
  const std::string file = doc.file();
  if (ctx.may_release_case) doc.releaseValue();
  return runScene(std::move(scene), file, ctx);
}

std::optional<bridge::Estimate> estimateScene(const bridge::JsonDocument& doc) {
  const Scene scene = parseScene(doc.root());
  return sceneEstimate(scene, chooseDt(scene, criticalTimeStep(scene), doc.file()));
}

}  // namespace

std::vector<bridge::CaseKind> caseKinds() {
  return {{"micro.scene", "fine DEM of explicit spheres, rigid multi-sphere blocks and planar walls (docs/micro.md)",
           checkScene, runSceneCase, estimateScene},
          nettingTensileKind(),
          cellKind(),
          lab::confinedCompressionKind(),
          lab::unconfinedCompressionKind(),
          lab::unconfinedImpactKind(),
          lab::interfaceShearKind(),
          lab::structureImpactKind()};
}

}  // namespace gabion::micro
