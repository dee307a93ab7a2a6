# minkq_abi_checks(TARGET HEADER MACRO ABI_DEFINE NODE_PREFIX): the ctest test of what a shared
# library exports (labels cpu and abi):
#   exports_<target>  its dynamic symbols are exactly the functions HEADER marks MACRO, at the
#                     symbol version <NODE_PREFIX><ABI_DEFINE> (check_exports.cmake).
function(minkq_abi_checks target header macro abi_define node_prefix)
  add_test(NAME exports_${target}
           COMMAND ${CMAKE_COMMAND} -DNM=${CMAKE_NM} -DLIBRARY=$<TARGET_FILE:${target}> -DHEADER=${header}
                   -DMACRO=${macro} -DABI_DEFINE=${abi_define} -DNODE_PREFIX=${node_prefix}
                   -P ${CMAKE_CURRENT_FUNCTION_LIST_DIR}/check_exports.cmake)
  set_tests_properties(exports_${target} PROPERTIES LABELS "cpu;abi")
endfunction()
