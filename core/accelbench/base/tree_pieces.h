// A tree built by several tasks at once, put together into the arrays one task would have
// written. Our trees are flat arrays in a fixed order (depth-first for the binary BVHs and the
// kd-tree, by node for the wide BVH), with a second array of leaf items (the kd-tree's
// primitive indices, the wide BVH's triangle packets). A subtree handed out to another task
// cannot know where it will land — that depends on the size of everything before it — so it
// is written into a piece of its own, with indices local to the piece, and its place in the
// parent's piece is recorded as a hole. Once every task is done, layout() sizes the holes
// and assemble() copies every piece to its final place (once, in parallel), moving each
// node's references by where their piece landed. Copying each node once costs less than
// appending each finished subtree to its parent's piece, which copies a node once per task
// above it.
//
// A hole is inserted before the parent piece's node `node_at` and item `item_at` (its sizes
// then when the subtree was handed out); holes at the same position follow in the order they
// were recorded. The hole's `owner` is the parent's node whose references point into the
// hole's piece (the binary BVH's node whose second child was handed out: index 0 there);
// every other node's references are local to its own piece.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <vector>

#include "accelbench/base/parallel.h"

namespace accelbench {

template <class Node, class Item, class NodeVec = std::vector<Node>, class ItemVec = std::vector<Item>>
struct TreePiece {
    struct Hole {
        uint32_t node_at = 0, item_at = 0;
        uint32_t owner = 0;
        std::unique_ptr<TreePiece> piece;
    };

    NodeVec nodes;
    ItemVec items;
    std::vector<Hole> holes;  // in the order recorded (depth-first)

    // Records `child` as the subtree at the current end of this piece, referenced by node `owner`.
    void add_hole(uint32_t owner, std::unique_ptr<TreePiece> child) {
        holes.push_back({uint32_t(nodes.size()), uint32_t(items.size()), owner, std::move(child)});
    }

    // Where this piece's local indices land (after layout()).
    class Map {
    public:
        explicit Map(const TreePiece& p) : p_(p) {}
        uint64_t node(uint32_t local) const { return p_.node_start_ + local + shift(local, &Hole::node_at, true); }
        uint64_t item(uint32_t local) const { return p_.item_start_ + local + shift(local, &Hole::item_at, false); }

    private:
        // The sizes of the holes inserted at or before `local` (at most the count of them).
        uint64_t shift(uint32_t local, uint32_t Hole::*at, bool of_nodes) const {
            const size_t k = p_.holes_at_or_before(local, at);
            return k == 0 ? 0 : (of_nodes ? p_.node_prefix_[k - 1] : p_.item_prefix_[k - 1]);
        }
        const TreePiece& p_;
    };

    // Sizes every piece below this one and places them, this one at (node_start,
    // item_start); returns the total nodes and items.
    std::pair<uint64_t, uint64_t> layout(uint64_t node_start = 0, uint64_t item_start = 0) {
        node_start_ = node_start;
        item_start_ = item_start;
        node_prefix_.assign(holes.size(), 0);
        item_prefix_.assign(holes.size(), 0);
        uint64_t nodes_before = 0, items_before = 0;  // of the holes placed so far
        for (size_t k = 0; k < holes.size(); ++k) {
            Hole& h = holes[k];
            const auto [n, i] =
                h.piece->layout(node_start + h.node_at + nodes_before, item_start + h.item_at + items_before);
            nodes_before += n;
            items_before += i;
            node_prefix_[k] = nodes_before;
            item_prefix_[k] = items_before;
        }
        total_nodes_ = nodes.size() + nodes_before;
        total_items_ = items.size() + items_before;
        return {total_nodes_, total_items_};
    }

    // Copies every piece (after layout()) into out_nodes / out_items, calling
    // relocate(Node&, const Map& own, const Map& refs) on each node: `refs` is the map of the
    // piece its references point into (a hole's, for the hole's owner).
    template <class Relocate>
    void assemble(Node* out_nodes, Item* out_items, bool parallel, const Relocate& relocate) const {
        std::vector<const TreePiece*> all;
        collect(all);
        for_blocks(parallel, all.size(), 1,
                   [&](size_t k, size_t, size_t) { all[k]->copy(out_nodes, out_items, parallel, relocate); });
    }

    uint64_t total_nodes() const { return total_nodes_; }
    uint64_t total_items() const { return total_items_; }

private:
    // How many holes lie at or before local position `local` (holes are sorted by position).
    size_t holes_at_or_before(uint32_t local, uint32_t Hole::*at) const {
        return size_t(
            std::upper_bound(holes.begin(), holes.end(), local, [at](uint32_t v, const Hole& x) { return v < x.*at; }) -
            holes.begin());
    }

    void collect(std::vector<const TreePiece*>& all) const {
        all.push_back(this);
        for (const Hole& h : holes) h.piece->collect(all);
    }

    template <class Relocate>
    void copy(Node* out_nodes, Item* out_items, bool parallel, const Relocate& relocate) const {
        constexpr size_t kBlock = 16384;
        const Map own(*this);
        // The owners of holes, by node: their references use the hole's map.
        std::vector<std::pair<uint32_t, const TreePiece*>> owners;
        owners.reserve(holes.size());
        for (const Hole& h : holes) owners.push_back({h.owner, h.piece.get()});
        std::sort(owners.begin(), owners.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
        for (size_t k = 1; k < owners.size(); ++k)
            if (owners[k].first == owners[k - 1].first) throw std::logic_error("TreePiece: a node owns two holes");
        for_blocks(parallel, nodes.size(), kBlock, [&](size_t, size_t begin, size_t end) {
            auto owner = std::lower_bound(owners.begin(), owners.end(), uint32_t(begin),
                                          [](const auto& o, uint32_t v) { return o.first < v; });
            size_t k = holes_at_or_before(uint32_t(begin), &Hole::node_at);
            for (size_t i = begin; i < end; ++i) {
                while (k < holes.size() && holes[k].node_at <= i) ++k;
                Node n = nodes[i];
                if (owner != owners.end() && owner->first == i) {
                    relocate(n, own, Map(*owner->second));
                    ++owner;
                } else {
                    relocate(n, own, own);
                }
                out_nodes[node_start_ + i + (k ? node_prefix_[k - 1] : 0)] = n;
            }
        });
        for_blocks(parallel, items.size(), kBlock, [&](size_t, size_t begin, size_t end) {
            size_t k = holes_at_or_before(uint32_t(begin), &Hole::item_at);
            for (size_t i = begin; i < end; ++i) {
                while (k < holes.size() && holes[k].item_at <= i) ++k;
                out_items[item_start_ + i + (k ? item_prefix_[k - 1] : 0)] = items[i];
            }
        });
    }

    uint64_t node_start_ = 0, item_start_ = 0, total_nodes_ = 0, total_items_ = 0;
    std::vector<uint64_t> node_prefix_, item_prefix_;  // per hole: the sizes of the holes up to it
};

}  // namespace accelbench
