// Allocators whose resize() (and emplace_back() without arguments) leave new elements
// unwritten, for arrays that are sized first and then written, element by element, by the
// builders — some by several tasks, each its own part (base/parallel.h): value-initialising
// them would cost a serial pass over memory that is overwritten anyway. For
// implicit-lifetime types only (aggregates, trivially copyable): allocating the storage
// creates them.
#pragma once

#include <memory>
#include <new>
#include <type_traits>
#include <utility>

namespace accelbench {

// The construct() members of such an allocator (std::allocator_traits calls them).
struct DefaultInitConstruct {
    template <class U>
    void construct(U*) noexcept {
        static_assert(std::is_trivially_copyable_v<U> && std::is_trivially_destructible_v<U>);
    }
    template <class U, class... Args>
    void construct(U* p, Args&&... args) {
        ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
    }
};

// std::allocator with them.
template <class T>
struct DefaultInitAllocator : std::allocator<T>, DefaultInitConstruct {
    template <class U>
    struct rebind {
        using other = DefaultInitAllocator<U>;
    };
    DefaultInitAllocator() = default;
    template <class U>
    DefaultInitAllocator(const DefaultInitAllocator<U>&) noexcept {}
};

}  // namespace accelbench
