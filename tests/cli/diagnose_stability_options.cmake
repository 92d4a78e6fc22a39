# mppi-fit diagnose --stability-resamples reaches the stability selection: on a recording of the
# independent generator with a large throttle delay, 3 resamples are drawn (the log counts
# "of 3 resamples") and the delay is named; with 0 there is no stability selection (no resample
# lines) and the delay chosen on all the data is named. The independent generator's sweep passes
# both settings to its diagnoses: its runs.jsonl gives the named delay's inclusion frequency (a
# share of 3 resamples) and -1 with 0 resamples (the sweep's recordings: 10 s). Needs BIN_DIR,
# WORK_DIR and SOURCE_DIR.
set(out "${WORK_DIR}/diagnose_stability_options")
file(REMOVE_RECURSE "${out}")
file(MAKE_DIRECTORY "${out}")
execute_process(COMMAND "${BIN_DIR}/mppi-fit" diagnose synth --generator independent --out "${out}/rec.csv"
                        --effect throttle_delay_s=0.15 --seed 3 --duration 20
                RESULT_VARIABLE rc OUTPUT_VARIABLE ignored ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "synth failed (${rc}): ${err}")
endif()
set(common diagnose --log "${out}/rec.csv" --params "${SOURCE_DIR}/data/config/autorally_single_track.yaml"
    --effects throttle_delay,throttle_lag --no-plots)
foreach(n 3 0)
  execute_process(COMMAND "${BIN_DIR}/mppi-fit" ${common} --stability-resamples ${n} --out "${out}/r${n}"
                  RESULT_VARIABLE rc OUTPUT_VARIABLE log ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "diagnose --stability-resamples ${n} failed (${rc}): ${err}")
  endif()
  if(NOT log MATCHES "named: throttle_delay")
    message(FATAL_ERROR "--stability-resamples ${n}: the throttle delay was not named:\n${log}")
  endif()
  if(n EQUAL 3 AND NOT err MATCHES "throttle_delay chosen in [0-3] of 3 resamples")
    message(FATAL_ERROR "--stability-resamples 3 did not give 3 resamples:\n${err}")
  endif()
  if(n EQUAL 0 AND err MATCHES "resamples")
    message(FATAL_ERROR "--stability-resamples 0 still resampled:\n${err}")
  endif()
endforeach()
foreach(n 3 0)
  execute_process(COMMAND "${BIN_DIR}/mppi-fit" diagnose sweep --generator independent --effects throttle_delay
                          --sizes large --seeds 1 --pairs 0 --clean 0 --duration 10 --stability-resamples ${n}
                          --min-inclusion 0.6 --out "${out}/sweep${n}"
                  RESULT_VARIABLE rc OUTPUT_VARIABLE log ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "sweep --stability-resamples ${n} failed (${rc}): ${err}")
  endif()
  if(NOT log MATCHES "stability selection: ${n} resamples, named at inclusion >= 0.60")
    message(FATAL_ERROR "the sweep did not take --stability-resamples ${n} --min-inclusion 0.6:\n${log}")
  endif()
  file(READ "${out}/sweep${n}/runs.jsonl" runs)
  if(n EQUAL 3 AND NOT runs MATCHES "\"named\":\\[\"throttle_delay\"\\],\"named_inclusion\":\\[(1\\.0|0\\.6666)")
    message(FATAL_ERROR "sweep with 3 resamples: no delay named at a share of 3 resamples >= 0.6:\n${runs}")
  endif()
  if(n EQUAL 0 AND NOT runs MATCHES "\"named_inclusion\":\\[-1\\.0\\]")
    message(FATAL_ERROR "sweep with 0 resamples still reports an inclusion frequency:\n${runs}")
  endif()
endforeach()
message(STATUS "PASS: the number of stability resamples reaches the selection")
