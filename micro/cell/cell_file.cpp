#include "micro/cell/cell_file.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "bridge/errors.hpp"
#include "bridge/output.hpp"

namespace gabion::micro {
namespace {

constexpr const char* kFormat = "gabion.cell/2";

nlohmann::json materialJson(const Material& m) {
  nlohmann::json j = {{"density_kg_m3", m.density_kg_m3},
                      {"normal_stiffness_N_m", m.normal_stiffness_N_m},
                      {"shear_stiffness_N_m", m.shear_stiffness_N_m},
                      {"friction", m.friction},
                      {"local_damping", m.local_damping},
                      {"viscous_damping_ratio", m.viscous_damping_ratio}};
  if (std::isfinite(m.normal_force_limit_N)) j["normal_force_limit_N"] = m.normal_force_limit_N;
  return j;
}

void push3(std::vector<double>& v, const Vec3& x) {
  v.push_back(x.x()), v.push_back(x.y()), v.push_back(x.z());
}

Vec3 at3(const std::vector<double>& v, std::size_t k) {
  return {v[3 * k], v[3 * k + 1], v[3 * k + 2]};
}

}  // namespace

Scene stateScene(const Scene& in, const Engine& engine) {
  Scene s = in;
  for (std::size_t k = 0; k < s.spheres.size(); ++k) {
    const BodyState b = engine.body(k);
    s.spheres[k].center_m = b.position_m;
    s.spheres[k].velocity_m_s = b.velocity_m_s;
    s.spheres[k].angular_velocity_rad_s = b.angular_velocity_rad_s;
  }
  for (std::size_t k = 0; k < s.blocks.size(); ++k) {
    const BodyState b = engine.body(s.spheres.size() + k);
    s.blocks[k].position_m = engine.blockFrameOrigin(k);
    s.blocks[k].orientation = engine.blockOrientation(k);
    s.blocks[k].velocity_m_s = b.velocity_m_s;
    s.blocks[k].angular_velocity_rad_s = b.angular_velocity_rad_s;
  }
  // Walls where the engine has them (their programs start again from there).
  for (std::size_t w = 0; w < s.walls.size() && w < engine.wallCount(); ++w)
    s.walls[w].point_m = engine.wallPosition(w);
  s.links.clear();
  for (std::size_t l = 0; l < in.links.size(); ++l) {
    if (engine.linkBroken(l)) continue;
    s.links.push_back(in.links[l]);
    if (in.links[l].law == LinkSpec::Law::Wire) {
      s.links.back().wire_state = engine.linkWireState(l);
      s.links.back().beam_state = engine.linkBeamState(l);
      // (a wire being pulled tight is tied where it got to: no one pulls it on)
      s.links.back().wire.rest_length_m = engine.linkRestLength(l);
      s.links.back().pull_force_N = 0.0;
    }
  }
  s.generated = nlohmann::json::object();
  s.save_cell = false;
  return s;
}

void writeCellFile(const std::filesystem::path& path, const Scene& in, const Engine& engine,
                   const nlohmann::json& summary) {
  bridge::H5Writer h5(path);
  // In index order (an array: a JSON object would sort them by name).
  nlohmann::json materials = nlohmann::json::array();
  for (const Material& m : in.materials) {
    nlohmann::json j = materialJson(m);
    j["name"] = m.name;
    materials.push_back(j);
  }
  // Spheres: static attributes from the input, state from the engine.
  {
    std::vector<double> x, v, w, r, mass, inertia;
    std::vector<long long> material, group, fixed;
    for (std::size_t s = 0; s < in.spheres.size(); ++s) {
      const SphereSpec& sp = in.spheres[s];
      const BodyState b = engine.body(s);
      push3(x, b.position_m), push3(v, b.velocity_m_s), push3(w, b.angular_velocity_rad_s);
      r.push_back(sp.radius_m), mass.push_back(sphereMass(in, sp)), inertia.push_back(sphereInertia(in, sp));
      material.push_back(sp.material), group.push_back(sp.group), fixed.push_back(sp.fixed ? 1 : 0);
    }
    const std::size_t n = in.spheres.size();
    h5.write("/spheres/center_m", x, {n, 3}, "m");
    h5.write("/spheres/velocity_m_s", v, {n, 3}, "m/s");
    h5.write("/spheres/angular_velocity_rad_s", w, {n, 3}, "rad/s");
    h5.write("/spheres/radius_m", r, "m");
    h5.write("/spheres/mass_kg", mass, "kg");
    h5.write("/spheres/inertia_kg_m2", inertia, "kg m2");
    h5.writeInts("/spheres/material", material);
    h5.writeInts("/spheres/group", group);
    h5.writeInts("/spheres/fixed", fixed);
  }
  // Blocks: members in the block's own frame, the pose the engine has.
  {
    std::vector<double> members, radii, pos, q, v, w;
    std::vector<long long> count, material, group, fixed;
    for (std::size_t b = 0; b < in.blocks.size(); ++b) {
      const BlockSpec& spec = in.blocks[b];
      const BodyState s = engine.body(in.spheres.size() + b);
      const Eigen::Quaterniond o = engine.blockOrientation(b);
      push3(pos, engine.blockFrameOrigin(b));
      q.push_back(o.w()), q.push_back(o.x()), q.push_back(o.y()), q.push_back(o.z());
      push3(v, s.velocity_m_s), push3(w, s.angular_velocity_rad_s);
      for (std::size_t k = 0; k < spec.member_radii_m.size(); ++k)
        push3(members, spec.member_centers_m[k]), radii.push_back(spec.member_radii_m[k]);
      count.push_back(static_cast<long long>(spec.member_radii_m.size()));
      material.push_back(spec.material), group.push_back(spec.group), fixed.push_back(spec.fixed ? 1 : 0);
    }
    const std::size_t n = in.blocks.size();
    h5.writeInts("/blocks/member_count", count);
    h5.write("/blocks/member_center_m", members, {radii.size(), 3}, "m");
    h5.write("/blocks/member_radius_m", radii, "m");
    h5.write("/blocks/position_m", pos, {n, 3}, "m");
    h5.write("/blocks/orientation", q, {n, 4}, "1");
    h5.write("/blocks/velocity_m_s", v, {n, 3}, "m/s");
    h5.write("/blocks/angular_velocity_rad_s", w, {n, 3}, "rad/s");
    h5.writeInts("/blocks/material", material);
    h5.writeInts("/blocks/group", group);
    h5.writeInts("/blocks/fixed", fixed);
  }
  // Links still acting, with their laws and wire states; wire curves shared.
  {
    std::vector<long long> a, b, law, curve;
    std::vector<double> rest, k, tension_only, rupture, plastic, reached;
    std::vector<double> beam, beam_shear, beam_moment, beam_dissipated;  // beams: k_s, k_b, M_p, L; state
    std::vector<bridge::WireCurve> curves;
    for (std::size_t l = 0; l < in.links.size(); ++l) {
      if (engine.linkBroken(l)) continue;
      const LinkSpec& s = in.links[l];
      a.push_back(static_cast<long long>(s.a)), b.push_back(static_cast<long long>(s.b));
      const bool wire = s.law == LinkSpec::Law::Wire;
      law.push_back(wire ? 1 : 0);
      rest.push_back(wire ? s.wire.rest_length_m : s.linear.rest_length_m);
      k.push_back(wire ? 0.0 : s.linear.stiffness_N_m);
      tension_only.push_back(!wire && s.linear.tension_only ? 1.0 : 0.0);
      rupture.push_back(wire ? 0.0 : s.linear.rupture_strain);
      const bridge::WireState st = wire ? engine.linkWireState(l) : bridge::WireState{};
      plastic.push_back(st.plastic_strain), reached.push_back(st.reached_strain);
      const bridge::WireBeamParams& bp = s.beam;
      const bridge::WireBeamState bs = wire ? engine.linkBeamState(l) : bridge::WireBeamState{};
      for (const double x : {bp.shear_N_m, bp.bending_N_m_rad, bp.active() ? bp.plastic_moment_N_m : 0.0, bp.length_m})
        beam.push_back(x);
      push3(beam_shear, bs.shear_N), push3(beam_moment, bs.moment_N_m), beam_dissipated.push_back(bs.dissipated_J);
      long long c = -1;
      if (wire) {
        auto it = std::find(curves.begin(), curves.end(), s.wire.curve);
        c = it - curves.begin();
        if (it == curves.end()) curves.push_back(s.wire.curve);
      }
      curve.push_back(c);
    }
    h5.writeInts("/links/a", a);
    h5.writeInts("/links/b", b);
    h5.writeInts("/links/law", law);
    h5.writeInts("/links/curve", curve);
    h5.write("/links/rest_length_m", rest, "m");
    h5.write("/links/stiffness_N_m", k, "N/m");
    h5.write("/links/tension_only", tension_only, "1");
    h5.write("/links/rupture_strain", rupture, "1");
    h5.write("/links/plastic_strain", plastic, "1");
    h5.write("/links/reached_strain", reached, "1");
    h5.write("/links/beam", beam, {a.size(), 4}, "N/m, N m/rad, N m, m");
    h5.write("/links/beam_shear_N", beam_shear, {a.size(), 3}, "N");
    h5.write("/links/beam_moment_N_m", beam_moment, {a.size(), 3}, "N m");
    h5.write("/links/beam_dissipated_J", beam_dissipated, "J");
    for (std::size_t c = 0; c < curves.size(); ++c) {
      h5.write("/links/curves/" + std::to_string(c) + "/strain", curves[c].strain(), "1");
      h5.write("/links/curves/" + std::to_string(c) + "/force_N", curves[c].force(), "N");
    }
    h5.writeInts("/links/curve_count", {static_cast<long long>(curves.size())});
  }
  h5.attribute("/", "format", kFormat);
  h5.attribute("/", "materials", materials.dump());
  h5.attribute("/", "summary", summary.dump());
  h5.commit();
}

void loadCellFile(const std::filesystem::path& path, Scene& scene) {
  const std::string file = path.string();
  const bridge::H5Reader h5(path);
  const std::string format = h5.attribute("/", "format");
  if (format.rfind("gabion.cell/", 0) != 0)
    throw bridge::InputError(file, "",
                             "not a Gabion cell file (its format is '" + format +
                                 "'; a cell file is written by a run with \"save_cell\": true)");
  if (format != kFormat)
    throw bridge::InputError(file, "",
                             "cell file format '" + format + "' is not the one this Gabion reads (" + kFormat +
                                 "): generate the cell again");
  const auto fail = [&](const std::string& what) { throw bridge::InputError(file, "", "damaged cell file: " + what); };
  // Materials: the scene's own win over the cell's of the same name.
  std::vector<int> material_of;  // cell material index -> scene material index
  nlohmann::json materials;
  try {
    materials = nlohmann::json::parse(h5.attribute("/", "materials"));
  } catch (const nlohmann::json::exception&) {
    fail("its materials attribute is not JSON");
  }
  if (!materials.is_array()) fail("its materials attribute is not a list");
  for (const nlohmann::json& m : materials) {
    const std::string name = m.value("name", "");
    const auto it =
        std::find_if(scene.materials.begin(), scene.materials.end(), [&](const Material& x) { return x.name == name; });
    if (it != scene.materials.end()) {
      material_of.push_back(static_cast<int>(it - scene.materials.begin()));
      continue;
    }
    Material mat;
    mat.name = name;
    mat.density_kg_m3 = m.value("density_kg_m3", 0.0);
    mat.normal_stiffness_N_m = m.value("normal_stiffness_N_m", 0.0);
    mat.shear_stiffness_N_m = m.value("shear_stiffness_N_m", 0.0);
    mat.friction = m.value("friction", 0.0);
    mat.local_damping = m.value("local_damping", 0.0);
    mat.viscous_damping_ratio = m.value("viscous_damping_ratio", 0.0);
    if (m.contains("normal_force_limit_N")) mat.normal_force_limit_N = m["normal_force_limit_N"].get<double>();
    material_of.push_back(static_cast<int>(scene.materials.size()));
    scene.materials.push_back(mat);
  }
  const auto mat = [&](double m) {
    const auto i = static_cast<long long>(m);
    if (i < 0 || i >= static_cast<long long>(material_of.size())) fail("a material index out of range");
    return material_of[static_cast<std::size_t>(i)];
  };
  const auto count = [&](const std::string& ds, std::size_t n, std::size_t cols) {
    const auto d = h5.dims(ds);
    const std::size_t got = d.empty() ? 0 : d[0] * (d.size() > 1 ? d[1] : 1);
    if (got != n * cols) fail(ds + " does not have " + std::to_string(n) + " rows");
    return h5.read(ds);
  };
  // Spheres.
  const std::size_t first_sphere = scene.spheres.size();
  const auto ns = h5.dims("/spheres/radius_m").empty() ? 0 : h5.dims("/spheres/radius_m")[0];
  {
    const auto x = count("/spheres/center_m", ns, 3), v = count("/spheres/velocity_m_s", ns, 3),
               w = count("/spheres/angular_velocity_rad_s", ns, 3), r = count("/spheres/radius_m", ns, 1),
               m = count("/spheres/mass_kg", ns, 1), inertia = count("/spheres/inertia_kg_m2", ns, 1),
               material = count("/spheres/material", ns, 1), group = count("/spheres/group", ns, 1),
               fixed = count("/spheres/fixed", ns, 1);
    for (std::size_t s = 0; s < ns; ++s) {
      SphereSpec sp;
      sp.center_m = at3(x, s), sp.velocity_m_s = at3(v, s), sp.angular_velocity_rad_s = at3(w, s);
      sp.radius_m = r[s], sp.mass_kg = m[s], sp.inertia_kg_m2 = inertia[s], sp.material = mat(material[s]);
      sp.group = static_cast<int>(group[s]), sp.fixed = fixed[s] != 0.0;
      scene.spheres.push_back(sp);
    }
  }
  // Blocks.
  {
    const auto nb = h5.dims("/blocks/member_count").empty() ? 0 : h5.dims("/blocks/member_count")[0];
    const auto counts = count("/blocks/member_count", nb, 1);
    std::size_t members = 0;
    for (const double c : counts) members += static_cast<std::size_t>(c);
    const auto mc = count("/blocks/member_center_m", members, 3), mr = count("/blocks/member_radius_m", members, 1),
               pos = count("/blocks/position_m", nb, 3), q = count("/blocks/orientation", nb, 4),
               v = count("/blocks/velocity_m_s", nb, 3), w = count("/blocks/angular_velocity_rad_s", nb, 3),
               material = count("/blocks/material", nb, 1), group = count("/blocks/group", nb, 1),
               fixed = count("/blocks/fixed", nb, 1);
    std::size_t next = 0;
    for (std::size_t b = 0; b < nb; ++b) {
      BlockSpec spec;
      for (std::size_t k = 0; k < static_cast<std::size_t>(counts[b]); ++k, ++next)
        spec.member_centers_m.push_back(at3(mc, next)), spec.member_radii_m.push_back(mr[next]);
      spec.position_m = at3(pos, b);
      spec.orientation = Eigen::Quaterniond(q[4 * b], q[4 * b + 1], q[4 * b + 2], q[4 * b + 3]).normalized();
      spec.velocity_m_s = at3(v, b), spec.angular_velocity_rad_s = at3(w, b);
      spec.material = mat(material[b]), spec.group = static_cast<int>(group[b]), spec.fixed = fixed[b] != 0.0;
      scene.blocks.push_back(spec);
    }
  }
  // Links.
  {
    const auto nl = h5.dims("/links/a").empty() ? 0 : h5.dims("/links/a")[0];
    const auto a = count("/links/a", nl, 1), b = count("/links/b", nl, 1), law = count("/links/law", nl, 1),
               curve = count("/links/curve", nl, 1), rest = count("/links/rest_length_m", nl, 1),
               k = count("/links/stiffness_N_m", nl, 1), tension = count("/links/tension_only", nl, 1),
               rupture = count("/links/rupture_strain", nl, 1), plastic = count("/links/plastic_strain", nl, 1),
               reached = count("/links/reached_strain", nl, 1), beam = count("/links/beam", nl, 4),
               beam_shear = count("/links/beam_shear_N", nl, 3), beam_moment = count("/links/beam_moment_N_m", nl, 3),
               beam_dissipated = count("/links/beam_dissipated_J", nl, 1);
    const auto nc = static_cast<std::size_t>(count("/links/curve_count", 1, 1)[0]);
    std::vector<bridge::WireCurve> curves;
    for (std::size_t c = 0; c < nc; ++c)
      curves.emplace_back(h5.read("/links/curves/" + std::to_string(c) + "/strain"),
                          h5.read("/links/curves/" + std::to_string(c) + "/force_N"));
    for (std::size_t l = 0; l < nl; ++l) {
      LinkSpec s;
      if (a[l] < 0 || b[l] < 0 || a[l] >= static_cast<double>(ns) || b[l] >= static_cast<double>(ns))
        fail("a link joins a sphere the file does not have");
      s.a = first_sphere + static_cast<std::size_t>(a[l]);
      s.b = first_sphere + static_cast<std::size_t>(b[l]);
      if (law[l] == 1.0) {
        const auto c = static_cast<long long>(curve[l]);
        if (c < 0 || c >= static_cast<long long>(nc)) fail("a wire link names a curve the file does not have");
        s.law = LinkSpec::Law::Wire;
        s.wire.curve = curves[static_cast<std::size_t>(c)];
        s.wire.rest_length_m = rest[l];
        s.wire_state = {plastic[l], reached[l]};
        if (beam[4 * l + 1] > 0.0) {
          s.beam = {beam[4 * l], beam[4 * l + 1], beam[4 * l + 2], beam[4 * l + 3]};
          if (!(s.beam.shear_N_m > 0.0 && s.beam.plastic_moment_N_m > 0.0 && s.beam.length_m > 0.0))
            fail("a bending wire with a stiffness, plastic moment or length that is not > 0");
          s.beam_state = {at3(beam_shear, l), at3(beam_moment, l), beam_dissipated[l]};
        }
      } else {
        s.linear.rest_length_m = rest[l];
        s.linear.stiffness_N_m = k[l];
        s.linear.tension_only = tension[l] != 0.0;
        s.linear.rupture_strain = rupture[l];
      }
      scene.links.push_back(s);
    }
  }
}

}  // namespace gabion::micro
