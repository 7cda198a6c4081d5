#include "micro/netting/scene_nettings.hpp"

#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "micro/netting/mesh.hpp"
#include "micro/netting/netting_input.hpp"
#include "micro/particles.hpp"

namespace gabion::micro {

using bridge::Check;
using bridge::JsonReader;

void addNettings(const JsonReader& root, Scene& scene) {
  const std::vector<JsonReader> entries = root.objects("nettings");
  for (std::size_t n = 0; n < entries.size(); ++n) {
    const JsonReader& r = entries[n];
    const NettingInput in = parseNetting(r);
    const bool box = r.has("box");
    if (box == r.has("sheet")) r.failHere("give either a `sheet` or a `box`");
    const JsonReader shape = r.object(box ? "box" : "sheet");
    const Vec3 origin = shape.vec3("origin_m", Vec3::Zero());
    Netting net;
    std::map<std::string, std::vector<std::uint32_t>> sets;
    try {
      if (box) {
        net = closedBox(in.mesh, shape.number("edge_m", Check::Positive), shape.boolean("open_top", false));
        const char* names[6] = {"bottom", "top", "front", "back", "left", "right"};
        for (std::size_t f = 0; f < 6; ++f)
          if (!net.faces[f].empty()) sets[names[f]] = net.faces[f];
      } else {
        const double width = shape.number("width_m", Check::Positive),
                     length = shape.number("length_m", Check::Positive);
        net = flatSheet(in.mesh, width, length);
        sets["bottom_edge"] = net.bottom_edge;
        sets["top_edge"] = net.top_edge;
      }
    } catch (const std::invalid_argument& e) {
      shape.failHere(e.what());
    }
    const int group = static_cast<int>(r.integer("group", 0, 0));
    if (group >= kGroupCount) r.fail("group", "contact groups are 0 .. " + std::to_string(kGroupCount - 1));
    std::vector<char> fixed(net.node_m.size(), 0);
    if (r.has("fix")) {
      const nlohmann::json& fix = r.raw("fix");
      if (!fix.is_array()) r.fail("fix", "expected an array of node-set names");
      for (std::size_t k = 0; k < fix.size(); ++k) {
        const auto it = fix[k].is_string() ? sets.find(fix[k].get<std::string>()) : sets.end();
        if (it == sets.end()) {
          std::string known;
          for (const auto& [name, ids] : sets) known += (known.empty() ? "" : ", ") + name;
          r.failElement("fix", k, "unknown node set (a " + std::string(box ? "box" : "sheet") + " has: " + known + ")");
        }
        for (const std::uint32_t id : it->second) fixed[id] = 1;
      }
    }
    Material contact = in.contact;
    contact.name = "netting_" + std::to_string(n);
    const auto material = static_cast<int>(scene.materials.size());
    scene.materials.push_back(contact);
    const std::size_t first = scene.spheres.size();
    for (std::size_t k = 0; k < net.node_m.size(); ++k) {
      SphereSpec sp;
      sp.center_m = origin + net.node_m[k];
      sp.radius_m = net.node_radius_m;
      sp.mass_kg = net.node_mass_kg[k];
      sp.inertia_kg_m2 = net.node_inertia_kg_m2[k];
      sp.mass_scale = in.mesh.node_mass_scale;
      sp.material = material;
      sp.group = group;
      sp.fixed = fixed[k] != 0;
      scene.spheres.push_back(sp);
    }
    for (const NettingLink& l : net.links) scene.links.push_back(linkSpec(in.mesh, l, first));
  }
}

}  // namespace gabion::micro
