# `mpirun -n 3 minkq-mpi query MESH ...` prints the digests `minkq query MESH ...` prints, for
# one partition kind and every mode, with and without --leaf-exact.
foreach(mode box sphere capsule_ray capsule_exact "box;--leaf-exact" "capsule_exact;--leaf-exact")
  execute_process(COMMAND ${MINKQ} query ${MESH} --radius 0.3 --mode ${mode} --backend cpu
                  OUTPUT_VARIABLE single RESULT_VARIABLE single_code)
  execute_process(COMMAND ${MPIEXEC} -n 3 ${MINKQ_MPI} query ${MESH} --radius 0.3 --mode ${mode}
                          --partition ${PARTITION} --seed 7
                  OUTPUT_VARIABLE distributed ERROR_VARIABLE errors RESULT_VARIABLE distributed_code)
  if(NOT single_code EQUAL 0 OR NOT distributed_code EQUAL 0)
    message(FATAL_ERROR "${mode}: minkq exited ${single_code}, minkq-mpi ${distributed_code}: ${errors}")
  endif()
  string(REGEX MATCHALL "(vt|ee) candidates [0-9]+ digest [0-9a-f]+" want "${single}")
  string(REGEX MATCHALL "(vt|ee) candidates [0-9]+ digest [0-9a-f]+" got "${distributed}")
  list(LENGTH want lines)
  if(NOT lines EQUAL 2 OR NOT want STREQUAL got)
    message(FATAL_ERROR "${mode}, ${PARTITION}: minkq query printed\n${single}\nminkq-mpi printed\n${distributed}")
  endif()
  message(STATUS "${mode}, ${PARTITION}: ${got}")
endforeach()
message(STATUS "minkq-mpi printed, for the last mode:\n${distributed}")
