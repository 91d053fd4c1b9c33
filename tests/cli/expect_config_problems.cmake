# Runs `csgtile validate-config FILE` and checks that it fails naming each problem and line.
execute_process(COMMAND ${BIN} validate-config ${FILE} RESULT_VARIABLE rc
                OUTPUT_VARIABLE out ERROR_VARIABLE err)
set(all "${out}${err}")
if(rc EQUAL 0)
  message(FATAL_ERROR "validate-config accepted a broken config:\n${all}")
endif()
foreach(expected "5: queue.max_attmpts" "7: queue.lease_seconds" "11: kernel.chordal_tolerance")
  string(FIND "${all}" "${expected}" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "expected '${expected}' in:\n${all}")
  endif()
endforeach()
message(STATUS "validate-config reported all three problems:\n${all}")
