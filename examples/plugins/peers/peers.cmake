# The open peers as plugins (tinybvh_plugin.cpp, bvh2_plugin.cpp), built where their sources
# are: accelbench_peer_plugins(PEERS_DIR OUTPUT_DIR PLUGIN_TARGET) with PEERS_DIR holding
# tinybvh/tiny_bvh.h and bvh-v2/bvh/v2/bvh.h (../shared/peers beside this tree, see its
# README). A library that is not there is skipped with one line saying so. Included by this
# tree's CMakeLists.txt (build/peers/) and by examples/plugins/CMakeLists.txt.
set(ACCELBENCH_PEER_PLUGIN_SOURCES ${CMAKE_CURRENT_LIST_DIR})

function(accelbench_peer_plugins peers_dir output_dir plugin_target)
  set(peer_plugins)
  if(EXISTS ${peers_dir}/tinybvh/tiny_bvh.h)
    add_library(peer_plugin_tinybvh MODULE ${ACCELBENCH_PEER_PLUGIN_SOURCES}/tinybvh_plugin.cpp)
    target_include_directories(peer_plugin_tinybvh SYSTEM PRIVATE ${peers_dir}/tinybvh)
    set_target_properties(peer_plugin_tinybvh PROPERTIES OUTPUT_NAME tinybvh)
    list(APPEND peer_plugins peer_plugin_tinybvh)
  else()
    message(STATUS "peers: no ${peers_dir}/tinybvh/tiny_bvh.h; the tinybvh plugin is skipped")
  endif()
  if(EXISTS ${peers_dir}/bvh-v2/bvh/v2/bvh.h)
    add_library(peer_plugin_bvh2 MODULE ${ACCELBENCH_PEER_PLUGIN_SOURCES}/bvh2_plugin.cpp)
    target_include_directories(peer_plugin_bvh2 SYSTEM PRIVATE ${peers_dir}/bvh-v2)
    set_target_properties(peer_plugin_bvh2 PROPERTIES OUTPUT_NAME bvh2)
    list(APPEND peer_plugins peer_plugin_bvh2)
  else()
    message(STATUS "peers: no ${peers_dir}/bvh-v2/bvh/v2/bvh.h; the bvh v2 plugin is skipped")
  endif()
  foreach(plugin ${peer_plugins})
    # The libraries' own code is not held to our warnings (included as SYSTEM); the plugin
    # files are. tinybvh starts threads (std::thread) for its threaded builds.
    target_link_libraries(${plugin} PRIVATE ${plugin_target} Threads::Threads)
    target_compile_features(${plugin} PRIVATE cxx_std_20)
    target_compile_options(${plugin} PRIVATE -O3 -Wall -Wextra -Werror)
    set_target_properties(${plugin} PROPERTIES PREFIX "" CXX_VISIBILITY_PRESET hidden
                          LIBRARY_OUTPUT_DIRECTORY ${output_dir})
  endforeach()
endfunction()
