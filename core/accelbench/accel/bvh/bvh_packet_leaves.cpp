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

void BvhPacketLeaves::build(const FlatBvh& bvh) {
    packets.clear();
    first_packet.assign(bvh.nodes.size(), 0);
    uint32_t slots[WbvhTriPacket::kLanes];
    for (size_t i = 0; i < bvh.nodes.size(); ++i) {
        const BvhNode& node = bvh.nodes[i];
        if (!node.is_leaf()) continue;
        first_packet[i] = uint32_t(packets.size());
        for (uint32_t done = 0; done < node.prim_count(); done += WbvhTriPacket::kLanes) {
            const uint32_t lanes = std::min<uint32_t>(WbvhTriPacket::kLanes, node.prim_count() - done);
            for (uint32_t k = 0; k < lanes; ++k) slots[k] = node.first_prim() + done + k;
            packets.push_back(pack_triangles(bvh, {slots, lanes}));
        }
    }
}

}  // namespace accelbench
