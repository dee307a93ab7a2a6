# minkq_abi_checks(TARGET HEADERS MACRO ABI_DEFINE NODE_PREFIX BASELINE [MORE_HEADERS...]): the two
# ctest tests of what a shared library exports (labels cpu and abi). HEADERS: the library's public
# headers, a list (quoted), the one holding ABI_DEFINE first, then the parts it includes.
#   exports_<target>  its dynamic symbols are exactly the functions HEADERS mark MACRO, at the
#                     symbol version <NODE_PREFIX><ABI_DEFINE> (check_exports.cmake);
#   abi_<target>      abidiff against the committed BASELINE passes, or ABI_DEFINE was bumped
#                     (check_abi.sh, which also says how to refresh the baseline).
# check_abi.sh needs abidw and abidiff (Debian: abigail-tools, which build.sh installs); where
# they are missing the abi_ test fails and says so.
function(minkq_abi_checks target headers macro abi_define node_prefix baseline)
  list(GET headers 0 header)
  set(parts ${headers})
  list(REMOVE_AT parts 0)
  string(REPLACE ";" "," part_list "${parts}")
  add_test(NAME exports_${target}
           COMMAND ${CMAKE_COMMAND} -DNM=${CMAKE_NM} -DLIBRARY=$<TARGET_FILE:${target}> -DHEADER=${header}
                   -DPARTS=${part_list}
                   -DMACRO=${macro} -DABI_DEFINE=${abi_define} -DNODE_PREFIX=${node_prefix}
                   -P ${CMAKE_CURRENT_FUNCTION_LIST_DIR}/check_exports.cmake)
  add_test(NAME abi_${target}
           COMMAND ${CMAKE_CURRENT_FUNCTION_LIST_DIR}/check_abi.sh $<TARGET_FILE:${target}> ${header} ${abi_define}
                   ${baseline} ${parts} ${ARGN})
  set_tests_properties(exports_${target} abi_${target} PROPERTIES LABELS "cpu;abi")
endfunction()
