#include "micro/links.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace gabion::micro {

Links::Links(const std::vector<LinkSpec>& specs, std::size_t particles) : particles_(particles) {
  for (const LinkSpec& s : specs) {
    a_.push_back(static_cast<std::uint32_t>(s.a));
    b_.push_back(static_cast<std::uint32_t>(s.b));
    law_.push_back(s.law);
    if (s.law == LinkSpec::Law::Linear) {
      law_index_.push_back(static_cast<std::uint32_t>(linear_.size()));
      linear_.push_back(s.linear);
      wire_rest_.push_back(0.0);
      continue;
    }
    // A netting has a handful of distinct curves (mesh wire, twists, selvedge).
    auto same = std::find(wires_.begin(), wires_.end(), s.wire.curve);
    law_index_.push_back(static_cast<std::uint32_t>(same - wires_.begin()));
    if (same == wires_.end()) wires_.push_back(s.wire.curve);
    wire_rest_.push_back(s.wire.rest_length_m);
  }
  for (const double L0 : wire_rest_) wire_inv_rest_.push_back(L0 > 0.0 ? 1.0 / L0 : 0.0);
  pulled_.assign(specs.size(), 0);
  for (std::size_t l = 0; l < specs.size(); ++l)
    if (specs[l].pulled()) {
      pull_.push_back({static_cast<std::uint32_t>(l), specs[l].pull_force_N, specs[l].pull_min_m, 0.0});
      pulled_[l] = 1;
    }
  const std::size_t n = a_.size();
  // Each wire's constants side by side, for the elastic pass (evaluate).
  for (std::size_t l = 0; l < n; ++l) {
    const bool wire = law_[l] == LinkSpec::Law::Wire;
    const bridge::WireCurve* c = wire ? &wires_[law_index_[l]] : nullptr;
    wire_elastic_.push_back(wire ? c->elasticForce() : 0.0);
    wire_first_.push_back(wire ? c->strain()[0] : 0.0);
    wire_rupture_.push_back(wire ? c->ruptureStrain() : 0.0);
    general_.push_back(wire && !pulled_[l] ? 0 : 1);
  }
  slow_.assign(n, 0);
  wire_state_.clear();
  for (const LinkSpec& s : specs) wire_state_.push_back(s.wire_state);
  broken_.assign(n, 0);
  beam_of_.assign(n, kNoBeam);
  Beams& B = beams_;
  for (std::size_t l = 0; l < n; ++l)
    if (specs[l].law == LinkSpec::Law::Wire && specs[l].beam.active()) {
      beam_of_[l] = static_cast<std::uint32_t>(B.size());
      const bridge::WireBeamParams& p = specs[l].beam;
      B.link.push_back(static_cast<std::uint32_t>(l));
      B.shear_k.push_back(p.shear_N_m), B.bending_k.push_back(p.bending_N_m_rad);
      B.plastic_moment.push_back(p.plastic_moment_N_m), B.length.push_back(p.length_m);
      for (auto* v : {&B.sx, &B.sy, &B.sz, &B.mx, &B.my, &B.mz, &B.dissipated}) v->push_back(0.0);
      B.setState(B.size() - 1, specs[l].beam_state);
    }
  const std::size_t nb = B.size();
  for (auto* v : {&B.cx, &B.cy, &B.cz}) v->assign(nb, 0.0);
  for (auto* v : {&B.fx, &B.fy, &B.fz}) v->assign(nb + 1, 0.0);
  for (auto* v : {&B.tx, &B.ty, &B.tz}) v->assign(2 * (nb + 1), 0.0);
  B.slow.assign(nb, 0);
  B.broken.assign(nb, 0);
  for (auto* v : {&fx_, &fy_, &fz_, &tension_, &len_, &ux_, &uy_, &uz_}) v->assign(n, 0.0);
  // Incidence by particle id, links in increasing order at each node.
  std::vector<std::uint32_t> count(particles + 1, 0);
  for (std::size_t l = 0; l < n; ++l) ++count[a_[l] + 1], ++count[b_[l] + 1];
  std::vector<std::uint32_t> start(particles + 1, 0);
  for (std::size_t id = 0; id < particles; ++id) start[id + 1] = start[id] + count[id + 1];
  std::vector<std::uint32_t> link(2 * n);
  std::vector<double> sign(2 * n);
  std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
  for (std::size_t l = 0; l < n; ++l) {
    link[fill[a_[l]]] = static_cast<std::uint32_t>(l), sign[fill[a_[l]]++] = 1.0;
    link[fill[b_[l]]] = static_cast<std::uint32_t>(l), sign[fill[b_[l]]++] = -1.0;
  }
  node_begin_.push_back(0);
  for (std::size_t id = 0; id < particles; ++id) {
    if (start[id + 1] == start[id]) continue;
    node_id_.push_back(static_cast<std::uint32_t>(id));
    for (std::uint32_t q = start[id]; q < start[id + 1]; ++q)
      node_link_.push_back(link[q]), node_sign_.push_back(sign[q]);
    node_begin_.push_back(static_cast<std::uint32_t>(node_link_.size()));
  }
  // The same incidence padded to the largest number of links at a node
  // (a padding entry: the node's first link with sign 0, adding +0 to the
  // sum), so that nodeForces runs the same count at every node.
  for (std::size_t k = 0; k + 1 < node_begin_.size(); ++k)
    node_degree_ = std::max<std::size_t>(node_degree_, node_begin_[k + 1] - node_begin_[k]);
  const std::size_t nodes = node_id_.size();
  padded_link_.assign(nodes * node_degree_, 0);
  padded_sign_.assign(nodes * node_degree_, 0.0);
  for (std::size_t k = 0; k < nodes; ++k)
    for (std::size_t q = 0; q < node_degree_; ++q) {
      const std::uint32_t at = node_begin_[k] + static_cast<std::uint32_t>(q);
      const bool real = at < node_begin_[k + 1];
      padded_link_[k * node_degree_ + q] = node_link_[real ? at : node_begin_[k]];
      padded_sign_[k * node_degree_ + q] = real ? node_sign_[at] : 0.0;
    }
  std::vector<std::uint32_t> node_of(particles, 0);
  for (std::size_t k = 0; k < node_id_.size(); ++k) node_of[node_id_[k]] = static_cast<std::uint32_t>(k);
  for (std::size_t l = 0; l < n; ++l) ka_.push_back(node_of[a_[l]]), kb_.push_back(node_of[b_[l]]);
  for (const std::uint32_t l : B.link) B.ka.push_back(ka_[l]), B.kb.push_back(kb_[l]);
  // Each node's beams, in link order, padded likewise: a's force is minus
  // the beam's (its sign is that of the link's force on the node), its
  // torque the first of the beam's pair.
  if (nb == 0) return;
  std::vector<std::uint32_t> degree(nodes, 0);
  for (std::size_t k = 0; k < nodes; ++k)
    for (std::uint32_t q = node_begin_[k]; q < node_begin_[k + 1]; ++q) degree[k] += beam_of_[node_link_[q]] != kNoBeam;
  beam_degree_ = *std::max_element(degree.begin(), degree.end());
  const auto zero = static_cast<std::uint32_t>(nb);
  beam_force_at_.assign(nodes * beam_degree_, zero);
  beam_torque_at_.assign(nodes * beam_degree_, zero);
  beam_sign_.assign(nodes * beam_degree_, 0.0);
  for (std::size_t k = 0; k < nodes; ++k) {
    std::size_t at = k * beam_degree_;
    for (std::uint32_t q = node_begin_[k]; q < node_begin_[k + 1]; ++q) {
      const std::uint32_t beam = beam_of_[node_link_[q]];
      if (beam == kNoBeam) continue;
      const bool is_a = node_sign_[q] > 0.0;
      beam_force_at_[at] = beam, beam_sign_[at] = is_a ? -1.0 : 1.0;
      beam_torque_at_[at++] = is_a ? beam : zero + 1 + beam;
    }
  }
}

void Links::Beams::setState(std::size_t b, const bridge::WireBeamState& s) {
  sx[b] = s.shear_N.x(), sy[b] = s.shear_N.y(), sz[b] = s.shear_N.z();
  mx[b] = s.moment_N_m.x(), my[b] = s.moment_N_m.y(), mz[b] = s.moment_N_m.z();
  dissipated[b] = s.dissipated_J;
}

void Links::Beams::setActions(std::size_t b, const bridge::WireBeamResponse& r) {
  const std::size_t on_b = size() + 1 + b;
  fx[b] = r.force_b.x(), fy[b] = r.force_b.y(), fz[b] = r.force_b.z();
  tx[b] = r.torque_a.x(), ty[b] = r.torque_a.y(), tz[b] = r.torque_a.z();
  tx[on_b] = r.torque_b.x(), ty[on_b] = r.torque_b.y(), tz[on_b] = r.torque_b.z();
}

ExcludedPairs Links::excludedPairs() const {
  ExcludedPairs out;
  if (empty()) return out;
  const std::size_t particles = particles_;
  out.begin.assign(particles + 1, 0);
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
  for (std::size_t l = 0; l < size(); ++l) pairs.emplace_back(a_[l], b_[l]), pairs.emplace_back(b_[l], a_[l]);
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  for (const auto& [x, y] : pairs) ++out.begin[x + 1], out.ids.push_back(y);
  for (std::size_t id = 0; id < particles; ++id) out.begin[id + 1] += out.begin[id];
  return out;
}

// One link's whole law at this sub-step: its force, or its rupture (event,
// energy). A broken link keeps no force.
void Links::evaluateOne(std::size_t l, const double* X, const double* Y, const double* Z, double time_s, bool measure,
                        double& elastic, double& rupture, double& plastic, WorkerScratch& s) {
  const bool wire = law_[l] == LinkSpec::Law::Wire;
  // A wire's plastic work stays dissipated after it breaks.
  if (measure && wire) plastic += bridge::wireDissipatedEnergy(wires_[law_index_[l]], wire_rest_[l], wire_state_[l]);
  const std::uint32_t beam = beam_of_[l];
  if (broken_[l]) {
    fx_[l] = fy_[l] = fz_[l] = tension_[l] = 0.0;  // (the elastic pass may have written it)
    return;
  }
  const double length = len_[l];
  bridge::LinkResponse r;
  if (wire) {
    const bridge::WireCurve& c = wires_[law_index_[l]];
    const double L0 = wire_rest_[l];
    const bridge::WireResponse w = bridge::wireResponse(c, wire_state_[l], (length - L0) * wire_inv_rest_[l]);
    // (it held the energy of its last point when it went)
    const double held = w.breaks ? c.force().back() : w.force_N;
    r = {w.force_N, measure || w.breaks ? bridge::wireElasticEnergy(c, L0, held) : 0.0, w.breaks};
  } else {
    r = bridge::linearLinkResponse(linear_[law_index_[l]], length);
  }
  if (r.breaks) {
    // The energy the link held is lost with it.
    if (wire) {
      rupture += r.elastic_J;
    } else {
      bridge::LinearLinkParams intact = linear_[law_index_[l]];
      intact.rupture_strain = std::numeric_limits<double>::infinity();
      rupture += bridge::linearLinkResponse(intact, length).elastic_J;
    }
    broken_[l] = 1;
    fx_[l] = fy_[l] = fz_[l] = tension_[l] = 0.0;
    if (beam != kNoBeam) {
      // Its bending goes with it.
      bridge::WireBeamState bs = beams_.state(beam);
      rupture += bridge::wireBeamElasticEnergy(beams_.params(beam), bs, Vec3(ux_[l], uy_[l], uz_[l]));
      bs.shear_N.setZero(), bs.moment_N_m.setZero();
      beams_.setState(beam, bs);
      beams_.broken[beam] = 1;
    }
    const std::uint32_t i = ka_[l];
    const double h = 0.5 * length;
    s.link_events.push_back({time_s, l, Vec3(X[i] + h * ux_[l], Y[i] + h * uy_[l], Z[i] + h * uz_[l])});
    return;
  }
  // Tension pulls a towards b.
  fx_[l] = r.force_N * ux_[l], fy_[l] = r.force_N * uy_[l], fz_[l] = r.force_N * uz_[l];
  tension_[l] = r.force_N;
  if (measure) elastic += r.elastic_J;
}

void Links::evaluate(const double* X, const double* Y, const double* Z, std::size_t l0, std::size_t l1, double time_s,
                     bool measure, WorkerScratch& s) {
  double elastic = 0.0, rupture = 0.0, plastic = 0.0;
  // Geometry of every link of the range first, in one vectorised pass (the
  // square roots and divisions off the laws' branchy path): length and unit
  // vector from a to b.
  {
    const std::uint32_t *SA = ka_.data(), *SB = kb_.data();
    double *len = len_.data(), *ux = ux_.data(), *uy = uy_.data(), *uz = uz_.data();
#pragma omp simd
    for (std::size_t l = l0; l < l1; ++l) {
      const std::uint32_t i = SA[l], j = SB[l];
      const double ex = X[j] - X[i], ey = Y[j] - Y[i], ez = Z[j] - Z[i];
      const double length = std::sqrt(ex * ex + ey * ey + ez * ez);
      const double inv = length > 0.0 ? 1.0 / length : 0.0;
      len[l] = length, ux[l] = ex * inv, uy[l] = ey * inv, uz[l] = ez * inv;
    }
  }
  // The laws. Between the measuring steps, a first vectorised pass gives
  // every wire the force of its elastic line, F = max(0, E A (eps - eps_p)):
  // the law's answer for a wire below its backbone and rupture
  // (bridge::wireResponse), which is nearly every wire at nearly every
  // sub-step. The links it cannot answer (one reaching its backbone or
  // breaking, a broken link, a linear spring) then take the whole law, in
  // link order, as do all links on a measuring step (their energies are
  // summed in link order).
  // (a wire being pulled tight slides through its loops: its law waits, pull)
  const std::uint8_t* PULLED = pulled_.data();
  if (measure) {
    for (std::size_t l = l0; l < l1; ++l)
      if (!PULLED[l]) evaluateOne(l, X, Y, Z, time_s, measure, elastic, rupture, plastic, s);
  } else {
    const double *len = len_.data(), *ux = ux_.data(), *uy = uy_.data(), *uz = uz_.data();
    const double *IR = wire_inv_rest_.data(), *L0 = wire_rest_.data(), *E = wire_elastic_.data();
    const double *FIRST = wire_first_.data(), *RUP = wire_rupture_.data();
    const bridge::WireState* WS = wire_state_.data();
    const std::uint8_t *GEN = general_.data(), *BROKEN = broken_.data();
    double *FX = fx_.data(), *FY = fy_.data(), *FZ = fz_.data(), *T = tension_.data();
    std::uint8_t* slow = slow_.data();
#pragma omp simd
    for (std::size_t l = l0; l < l1; ++l) {
      const double eps = (len[l] - L0[l]) * IR[l];
      const double f = bridge::wireElasticLineForce(E[l], eps, WS[l].plastic_strain);
      const bool off = bridge::wireLeavesElasticLine(eps, WS[l].reached_strain, FIRST[l], RUP[l]);
      slow[l] = (GEN[l] | BROKEN[l] | (off ? 1 : 0)) != 0 ? 1 : 0;
      FX[l] = f * ux[l], FY[l] = f * uy[l], FZ[l] = f * uz[l];
      T[l] = f;
    }
    for (std::size_t l = l0; l < l1; ++l)
      if (slow[l] && !PULLED[l]) evaluateOne(l, X, Y, Z, time_s, measure, elastic, rupture, plastic, s);
  }
  if (!pull_.empty()) pull(l0, l1, s);
  s.link_elastic += elastic;
  s.link_rupture += rupture;
  s.link_plastic += plastic;
}

void Links::pull(std::size_t l0, std::size_t l1, WorkerScratch& s) {
  const auto first =
      std::lower_bound(pull_.begin(), pull_.end(), l0, [](const Pull& p, std::size_t l) { return p.link < l; });
  double work = 0.0;
  for (auto p = first; p != pull_.end() && p->link < l1; ++p) {
    const std::uint32_t l = p->link;
    if (!pulled_[l]) continue;  // (tied)
    const double L = len_[l];
    // (the pull's potential is F max(L, shortest): exact for any move)
    if (p->last_m > 0.0) work += p->force_N * (std::max(p->last_m, p->min_m) - std::max(L, p->min_m));
    p->last_m = L;
    const double f = L > p->min_m ? p->force_N : 0.0;
    fx_[l] = f * ux_[l], fy_[l] = f * uy_[l], fz_[l] = f * uz_[l];
    tension_[l] = f;
    if (f == 0.0) tie(*p);  // closed: tied at its shortest, its law acts from the next evaluation
  }
  s.link_pull_work += work;
}

void Links::tie(Pull& p) {
  const std::uint32_t l = p.link;
  pulled_[l] = 0, general_[l] = 0;
  wire_rest_[l] = p.min_m, wire_inv_rest_[l] = 1.0 / p.min_m;
  p.last_m = -1.0;
}

double Links::restLength(std::size_t l) const {
  if (pulled_[l]) {
    const auto p =
        std::lower_bound(pull_.begin(), pull_.end(), l, [](const Pull& q, std::size_t k) { return q.link < k; });
    return std::max(p->min_m, len_[l] > 0.0 ? len_[l] : wire_rest_[l]);
  }
  return law_[l] == LinkSpec::Law::Wire ? wire_rest_[l] : linear_[law_index_[l]].rest_length_m;
}

void Links::evaluateBeams(const double* X, const double* Y, const double* Z, const double* RX, const double* RY,
                          const double* RZ, std::size_t l0, std::size_t l1, bool measure, WorkerScratch& s) {
  Beams& B = beams_;
  const auto at = [&](std::size_t l) {
    return static_cast<std::size_t>(std::lower_bound(B.link.begin(), B.link.end(), l) - B.link.begin());
  };
  const std::size_t b0 = at(l0), b1 = at(l1), nb = B.size();
  double elastic = 0.0, plastic = 0.0;
  if (measure)  // (the plastic work before this increment, as the axial laws count theirs)
    for (std::size_t b = b0; b < b1; ++b) plastic += B.dissipated[b];
  // Every beam of the range in one vectorised pass, with the twist's series
  // (bridge::wireBeamSeriesAnswers: nearly every beam at nearly every step).
  // A beam it cannot answer keeps its state and takes the whole law after.
  {
    const std::uint32_t *KA = B.ka.data(), *KB = B.kb.data();
    const std::uint8_t* BROKEN = B.broken.data();
    const double *KS = B.shear_k.data(), *KBEND = B.bending_k.data(), *MP = B.plastic_moment.data(),
                 *LEN = B.length.data();
    double *SX = B.sx.data(), *SY = B.sy.data(), *SZ = B.sz.data(), *MX = B.mx.data(), *MY = B.my.data(),
           *MZ = B.mz.data(), *D = B.dissipated.data(), *CX = B.cx.data(), *CY = B.cy.data(), *CZ = B.cz.data();
    double *FX = B.fx.data(), *FY = B.fy.data(), *FZ = B.fz.data(), *TX = B.tx.data(), *TY = B.ty.data(),
           *TZ = B.tz.data();
    std::uint8_t* SLOW = B.slow.data();
#pragma GCC ivdep
    for (std::size_t b = b0; b < b1; ++b) {
      using bridge::BeamVec;
      const std::uint32_t i = KA[b], j = KB[b];
      const BeamVec c0(CX[b], CY[b], CZ[b]), c1(X[j] - X[i], Y[j] - Y[i], Z[j] - Z[i]);
      bridge::WireBeamParams p;
      p.shear_N_m = KS[b], p.bending_N_m_rad = KBEND[b], p.plastic_moment_N_m = MP[b], p.length_m = LEN[b];
      bridge::WireBeamActions a{BeamVec(SX[b], SY[b], SZ[b]), BeamVec(MX[b], MY[b], MZ[b]), D[b]};
      BeamVec ta, tb;
      double twist = 0.0;
      const BeamVec f =
          bridge::wireBeamIncrement(p, a, c0, c1, BeamVec(RX[i], RY[i], RZ[i]), BeamVec(RX[j], RY[j], RZ[j]),
                                    bridge::smallAngleSinCos, ta, tb, twist);
      const bool ok = bridge::wireBeamSeriesAnswers(bridge::dot(c0, c0), bridge::dot(c1, c1), twist) && !BROKEN[b];
      SLOW[b] = ok ? 0 : 1;
      SX[b] = ok ? a.shear.x : SX[b], SY[b] = ok ? a.shear.y : SY[b], SZ[b] = ok ? a.shear.z : SZ[b];
      MX[b] = ok ? a.moment.x : MX[b], MY[b] = ok ? a.moment.y : MY[b], MZ[b] = ok ? a.moment.z : MZ[b];
      D[b] = ok ? a.dissipated : D[b];
      CX[b] = ok ? c1.x : CX[b], CY[b] = ok ? c1.y : CY[b], CZ[b] = ok ? c1.z : CZ[b];
      FX[b] = f.x, FY[b] = f.y, FZ[b] = f.z;
      TX[b] = ta.x, TY[b] = ta.y, TZ[b] = ta.z;
      TX[nb + 1 + b] = tb.x, TY[nb + 1 + b] = tb.y, TZ[nb + 1 + b] = tb.z;
    }
  }
  for (std::size_t b = b0; b < b1; ++b)
    if (B.slow[b]) evaluateBeam(b, X, Y, Z, RX, RY, RZ);
  if (measure)
    for (std::size_t b = b0; b < b1; ++b)
      if (!B.broken[b])
        elastic += bridge::wireBeamElasticEnergy(B.params(b), B.state(b), Vec3(B.cx[b], B.cy[b], B.cz[b]).normalized());
  s.link_elastic += elastic;
  s.link_plastic += plastic;
}

void Links::evaluateBeam(std::size_t b, const double* X, const double* Y, const double* Z, const double* RX,
                         const double* RY, const double* RZ) {
  Beams& B = beams_;
  if (B.broken[b]) {
    B.setActions(b, {});
    return;
  }
  const std::uint32_t i = B.ka[b], j = B.kb[b];
  const Vec3 chord(X[j] - X[i], Y[j] - Y[i], Z[j] - Z[i]), last(B.cx[b], B.cy[b], B.cz[b]);
  const bool started = last.squaredNorm() > 0.0;  // (no increment at the first call)
  const Vec3 c0 = started ? last : chord;
  B.cx[b] = chord.x(), B.cy[b] = chord.y(), B.cz[b] = chord.z();
  const Vec3 ta = started ? Vec3(RX[i], RY[i], RZ[i]) : Vec3::Zero(),
             tb = started ? Vec3(RX[j], RY[j], RZ[j]) : Vec3::Zero();
  bridge::WireBeamState bs = B.state(b);
  B.setActions(b, bridge::wireBeamStep(B.params(b), bs, c0, chord, ta, tb));
  B.setState(b, bs);
}

void Links::addNodeBeams(double* FX, double* FY, double* FZ, double* TX, double* TY, double* TZ, std::size_t k0,
                         std::size_t k1) const {
  const std::size_t D = beam_degree_;
  const std::uint32_t *F = beam_force_at_.data(), *T = beam_torque_at_.data();
  const double* sign = beam_sign_.data();
  const double *fx = beams_.fx.data(), *fy = beams_.fy.data(), *fz = beams_.fz.data();
  const double *tx = beams_.tx.data(), *ty = beams_.ty.data(), *tz = beams_.tz.data();
  for (std::size_t k = k0; k < k1; ++k) {
    double sx = 0.0, sy = 0.0, sz = 0.0, ux = 0.0, uy = 0.0, uz = 0.0;
    for (std::size_t q = k * D; q < (k + 1) * D; ++q) {
      const std::uint32_t f = F[q], t = T[q];
      const double sg = sign[q];
      sx += sg * fx[f], sy += sg * fy[f], sz += sg * fz[f];
      ux += tx[t], uy += ty[t], uz += tz[t];
    }
    FX[k] += sx, FY[k] += sy, FZ[k] += sz;
    TX[k] += ux, TY[k] += uy, TZ[k] += uz;
  }
}

void Links::nodeForces(double* FX, double* FY, double* FZ, std::size_t k0, std::size_t k1) const {
  // (each node's links in link order, then its padding: a sum that starts
  // at +0 is never -0, and adding +-0 leaves it as it is)
  const std::size_t D = node_degree_;
  const std::uint32_t* link = padded_link_.data();
  const double *sign = padded_sign_.data(), *fx = fx_.data(), *fy = fy_.data(), *fz = fz_.data();
  for (std::size_t k = k0; k < k1; ++k) {
    double sx = 0.0, sy = 0.0, sz = 0.0;
    for (std::size_t q = k * D; q < (k + 1) * D; ++q) {
      const std::uint32_t l = link[q];
      const double sg = sign[q];
      sx += sg * fx[l], sy += sg * fy[l], sz += sg * fz[l];
    }
    FX[k] = sx, FY[k] = sy, FZ[k] = sz;
  }
}

void Links::archive(bridge::StateArchive& a) {
  const std::size_t n = size(), nb = beams_.size();
  std::vector<double> eps_p(n), eps_r(n);
  for (std::size_t l = 0; l < n; ++l)
    eps_p[l] = wire_state_[l].plastic_strain, eps_r[l] = wire_state_[l].reached_strain;
  a("wire_plastic_strain", eps_p), a("wire_reached_strain", eps_r);
  if (!pull_.empty()) {  // (a netting without them keeps its checkpoint's keys)
    std::vector<double> last;
    for (const Pull& p : pull_) last.push_back(p.last_m);
    a("pulled_last_length_m", last);  // (-1: tied)
    if (a.loading()) {
      if (last.size() != pull_.size())
        throw std::invalid_argument("checkpoint: lengths of another count than this run's wires pulled tight");
      for (std::size_t k = 0; k < pull_.size(); ++k)
        if (last[k] < 0.0)
          tie(pull_[k]);
        else
          pull_[k].last_m = last[k];
    }
  }
  a("broken", broken_);
  a("fx", fx_), a("fy", fy_), a("fz", fz_), a("tension", tension_);
  a("length", len_), a("ux", ux_), a("uy", uy_), a("uz", uz_);
  std::vector<Vec3> shear(nb), moment(nb), chord(nb), force(nb), torque_a(nb), torque_b(nb);
  std::vector<double> dissipated(nb);
  const Beams& B = beams_;
  for (std::size_t k = 0; k < nb; ++k) {
    const bridge::WireBeamState st = B.state(k);
    shear[k] = st.shear_N, moment[k] = st.moment_N_m, dissipated[k] = st.dissipated_J;
    chord[k] = Vec3(B.cx[k], B.cy[k], B.cz[k]), force[k] = Vec3(B.fx[k], B.fy[k], B.fz[k]);
    torque_a[k] = Vec3(B.tx[k], B.ty[k], B.tz[k]);
    torque_b[k] = Vec3(B.tx[nb + 1 + k], B.ty[nb + 1 + k], B.tz[nb + 1 + k]);
  }
  bridge::StateArchive b = a.group("beams");
  b("shear_N", shear), b("moment_N_m", moment), b("dissipated_J", dissipated);
  b("chord", chord), b("force", force), b("torque_a", torque_a), b("torque_b", torque_b);
  if (!a.loading()) return;
  // (a checkpoint of another netting: refused before any of it is used)
  const auto same = [&](std::size_t found, std::size_t expect, const char* what) {
    if (found != expect)
      throw std::invalid_argument(std::string("checkpoint: ") + what + " of another size than this run's links");
  };
  for (const std::size_t m : {eps_p.size(), eps_r.size(), broken_.size(), fx_.size(), tension_.size(), len_.size()})
    same(m, n, "a link field");
  for (const std::size_t m :
       {shear.size(), moment.size(), dissipated.size(), chord.size(), force.size(), torque_a.size(), torque_b.size()})
    same(m, nb, "a beam field");
  for (std::size_t l = 0; l < n; ++l) wire_state_[l] = {eps_p[l], eps_r[l]};
  for (std::size_t k = 0; k < nb; ++k) {
    beams_.broken[k] = broken_[beams_.link[k]];
    beams_.setState(k, {shear[k], moment[k], dissipated[k]});
    beams_.cx[k] = chord[k].x(), beams_.cy[k] = chord[k].y(), beams_.cz[k] = chord[k].z();
    beams_.setActions(k, {force[k], torque_a[k], torque_b[k]});
  }
}

}  // namespace gabion::micro
