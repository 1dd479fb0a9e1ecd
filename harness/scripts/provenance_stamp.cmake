# The provenance of the code being compiled, stamped at build time: every build runs
#   cmake -DSOURCE_DIR=<source tree> -DOUT=<build>/generated/provenance_stamp.cpp -P provenance_stamp.cmake
# (CMakeLists.txt, target accelbench_provenance_stamp) and OUT is rewritten only when the
# commit or the dirty flag changed, so an unchanged tree recompiles nothing. A binary's
# git_sha and git_dirty are then those of the sources it was built from, whatever the work
# tree, GIT_DIR or `git` on PATH are when it runs (csv/provenance.cpp).
#
# Dirty: the sources differ from the commit: a change to a tracked file outside results/
# (outputs, rewritten by a reference run while it measures), or a file git does not track
# under core/ or harness/, where the build compiles every .cpp it finds. Not a git checkout:
# git_sha "unknown", clean.

if(NOT SOURCE_DIR OR NOT OUT)
  message(FATAL_ERROR "provenance_stamp.cmake: give -DSOURCE_DIR=... -DOUT=...")
endif()
# The git of the build, about this source tree only.
unset(ENV{GIT_DIR})
unset(ENV{GIT_WORK_TREE})
unset(ENV{GIT_INDEX_FILE})

execute_process(COMMAND git -C "${SOURCE_DIR}" rev-parse --verify HEAD
                RESULT_VARIABLE rc OUTPUT_VARIABLE sha ERROR_QUIET OUTPUT_STRIP_TRAILING_WHITESPACE)
set(dirty false)
if(NOT rc EQUAL 0 OR NOT sha MATCHES "^[0-9a-f]+$")
  set(sha unknown)
else()
  execute_process(COMMAND git -C "${SOURCE_DIR}" status --porcelain --untracked-files=no -- . ":(exclude)results"
                  RESULT_VARIABLE rc_tracked OUTPUT_VARIABLE tracked ERROR_QUIET)
  execute_process(COMMAND git -C "${SOURCE_DIR}" status --porcelain --untracked-files=all -- core harness
                  RESULT_VARIABLE rc_untracked OUTPUT_VARIABLE untracked ERROR_QUIET)
  if(NOT rc_tracked EQUAL 0 OR NOT rc_untracked EQUAL 0 OR NOT tracked STREQUAL "" OR NOT untracked STREQUAL "")
    set(dirty true)
  endif()
endif()

file(WRITE "${OUT}.tmp"
"// Written at build time by harness/scripts/provenance_stamp.cmake: the sources compiled.\n"
"namespace accelbench {\n"
"extern const char* const kBuildGitSha;\n"
"extern const bool kBuildGitDirty;\n"
"const char* const kBuildGitSha = \"${sha}\";\n"
"const bool kBuildGitDirty = ${dirty};\n"
"}  // namespace accelbench\n")
# configure_file leaves OUT untouched when its contents would not change.
configure_file("${OUT}.tmp" "${OUT}" COPYONLY)
file(REMOVE "${OUT}.tmp")
