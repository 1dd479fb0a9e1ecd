#include "accelbench/accel/bvh/bvh_packet_leaves.h"

#include <algorithm>

namespace accelbench {

WbvhTriPacket pack_triangles(const FlatBvh& bvh, std::span<const uint32_t> slots) {
    WbvhTriPacket p{};
    for (int lane = 0; lane < WbvhTriPacket::kLanes; ++lane) {
        p.prim[lane] = kInvalidId;
        if (size_t(lane) >= slots.size()) continue;
        const uint32_t slot = slots[size_t(lane)];
        const LeafTriangle& tri = bvh.triangles[slot];
        const Vec3 v[3] = {tri.p0, tri.p1, tri.p2};
        for (int i = 0; i < 3; ++i)
            for (int a = 0; a < 3; ++a) p.v[i][a][lane] = v[i][a];
        p.prim[lane] = bvh.prim_ids[slot];
    }
    return p;
}

void BvhPacketLeaves::build(const FlatBvh& bvh, bool parallel) {
    // Blocks of nodes: each block's packets start where the blocks before it end (counted
    // first), so the packets lie in node order whatever the threads.
    constexpr size_t kBlock = 1 << 14;
    const size_t n = bvh.nodes.size();
    std::vector<uint32_t> block_start(block_count(n, kBlock) + 1, 0);
    auto packets_of = [&](const BvhNode& node) {
        return node.is_leaf() ? WbvhTriPacket::packets_for(node.prim_count()) : 0u;
    };
    for_blocks(parallel, n, kBlock, [&](size_t k, size_t begin, size_t end) {
        uint32_t count = 0;
        for (size_t i = begin; i < end; ++i) count += packets_of(bvh.nodes[i]);
        block_start[k + 1] = count;
    });
    for (size_t k = 1; k < block_start.size(); ++k) block_start[k] += block_start[k - 1];
    packets.resize(block_start.back());  // not written (DefaultInitAllocator)
    first_packet.resize(n);
    for_blocks(parallel, n, kBlock, [&](size_t k, size_t begin, size_t end) {
        uint32_t next = block_start[k];
        uint32_t slots[WbvhTriPacket::kLanes];
        for (size_t i = begin; i < end; ++i) {
            const BvhNode& node = bvh.nodes[i];
            first_packet[i] = node.is_leaf() ? next : 0;
            if (!node.is_leaf()) continue;
            for (uint32_t done = 0; done < node.prim_count(); done += WbvhTriPacket::kLanes) {
                const uint32_t lanes = std::min<uint32_t>(WbvhTriPacket::kLanes, node.prim_count() - done);
                for (uint32_t k2 = 0; k2 < lanes; ++k2) slots[k2] = node.first_prim() + done + k2;
                packets[next++] = pack_triangles(bvh, {slots, lanes});
            }
        }
    });
}

}  // namespace accelbench
