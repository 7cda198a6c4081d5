#pragma once
/// \file
/// The contact law on the touching pairs of the Verlet list, vectorised
/// (docs/micro.md, Speed): one row partition of the list per worker.
#include <cstdint>
#include <vector>

#include "micro/material_laws.hpp"
#include "micro/neighbour_grid.hpp"
#include "micro/particles.hpp"
#include "micro/worker_scratch.hpp"

namespace gabion::micro {

/// Evaluates the contacts of rows [r0, r1) of the list. Partition s owns the
/// particles of its rows: it clears and writes their forces and torques in
/// `p`; a partner beyond them (j > i always) goes to s's buffer (added in the
/// integration, in partition order), and each line of particles it first
/// writes there to s.lines_for[the line's partition] (line_partition: the
/// partition of each line of kParticlesPerLine particles). The last step's contacts are in
/// s.sets[hcur], this step's go to s.sets[hcur ^ 1]. An overlap above
/// max_overlap_ratio of the smaller radius marks s as failed, naming the pair
/// of the chunk that overlaps most.
void contactPartition(Particles& p, const NeighbourList& list, const MaterialLaws& laws, double dt,
                      double max_overlap_ratio, std::uint32_t r0, std::uint32_t r1, int hcur, bool measure,
                      const std::vector<std::uint32_t>& line_partition, WorkerScratch& s);

}  // namespace gabion::micro
