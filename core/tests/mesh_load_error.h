// The message of the exception load_mesh throws for a file the readers refuse; fails the
// calling test when nothing is thrown. Shared by the mesh readers' tests.
#pragma once

#include "accelbench/scene/mesh_io.h"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

namespace accelbench {

inline std::string mesh_load_error(const std::string& path) {
    try {
        load_mesh(path);
    } catch (const std::runtime_error& e) {
        return e.what();
    }
    ADD_FAILURE() << "load_mesh('" << path << "') did not throw";
    return "";
}

}  // namespace accelbench
