// The leaves of a FlatBvh as 4-triangle packets, for `bvh leaf_test=packet` (what auto picks
// where max_prims > 1, as split=sah's default): one SSE watertight test covers a leaf's
// triangles four at a time, the wide BVH's packet test (wbvh_simd.h, WbvhTriPacket and
// wbvh_leaf_test), which answers lane for lane as intersect_triangle does (wbvh_test compares
// the two forms).
//
// Why: SAH leaves hold several triangles (4-5 on the scanned models at traversal_cost 4),
// and the scalar loop tests them one after the other, each test a chain of data-dependent
// branches; the packet test does four in one branch-free pass. Measured (commit da52161,
// accel_bench, trace / Embree, two rounds, bunny / igea / conference / dragon): bvh
// split=sah traversal_cost=4 scalar 1.83 1.59 / 1.77 1.65 / 2.05 2.05 / 1.65 1.72, packet
// 1.32 1.32 / 1.41 1.46 / 1.88 1.83 / 1.47 1.50. With traversal_cost 1 (1.8 triangles a
// leaf, packets half empty) it gained on the bunny and the conference only (packet 1.56 /
// 1.81-1.84 / 1.82-1.91 / 2.01-2.05, scalar 1.66-1.84 / 1.82-1.86 / 2.02-2.19 / 1.98-1.99;
// without leaves sized to fill them there was no gain): the packets pay where the SAH makes leaves to fill
// them (bvh.h, traversal_cost).
//
// Kept beside the tree rather than in it: FlatBvh's nodes and slots stay what the builders,
// the reinsertion optimizer, the metrics and the tests read, and the report rows (one
// triangle a leaf) keep the scalar loop. Packed from the tree's triangle copies, which the
// Bvh then releases (only the scalar test reads them). A leaf finds its packets through
// first_packet[node index], a load whose address is known as soon as the node is, not after
// the node's own fields.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "accelbench/accel/bvh/flat_bvh.h"
#include "accelbench/accel/bvh/wbvh_simd.h"
#include "accelbench/base/parallel.h"

namespace accelbench {

// The packet of up to 4 slots of a finished tree (their triangles and scene indices), the
// lanes past slots.size() empty. The wide BVH fills its leaves with it too.
WbvhTriPacket pack_triangles(const FlatBvh& bvh, std::span<const uint32_t> slots);

struct BvhPacketLeaves {
    // Each leaf's triangles in slot order, ceil(count / 4) packets per leaf, the lanes past
    // the leaf's count masked off by the test (prim kInvalidId).
    std::vector<WbvhTriPacket, DefaultInitAllocator<WbvhTriPacket>> packets;
    // Per node: a leaf's first packet (unused for inner nodes).
    std::vector<uint32_t> first_packet;

    // Makes the packets of a finished (finalized) tree, on the build's threads when
    // `parallel` (the same packets).
    void build(const FlatBvh& bvh, bool parallel);
    size_t memory_bytes() const {
        return packets.size() * sizeof(WbvhTriPacket) + first_packet.size() * sizeof(uint32_t);
    }
};

}  // namespace accelbench
