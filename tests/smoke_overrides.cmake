# Per-case overrides that keep smoke runs short: GABION_SMOKE_SET_<case name>
# holds the extra arguments given to `gabion run` (a list of --set a.b=v).
# fit.micro resumes from OUTDIR/evaluations.jsonl by default; a smoke run starts afresh.
set(GABION_SMOKE_SET_fit_micro_wall --set resume=false)
# The netting tensile test to 5 cm of pull (the full test tears at about 0.2 m).
set(GABION_SMOKE_SET_micro_netting_tensile --set test.max_displacement_m=0.05)
set(GABION_SMOKE_SET_micro_netting_tensile_paper --set test.max_displacement_m=0.05)
set(GABION_SMOKE_SET_micro_netting_box --set run.duration_s=0.02)
set(GABION_SMOKE_SET_micro_block_fill --set run.duration_s=0.01)
set(GABION_SMOKE_SET_micro_cell --set fill.max_duration_s=0.01 --set vibration.max_duration_s=0.005 --set standing.max_duration_s=0.005)
# The lab tests start from the cell the micro_cell smoke run leaves (a
# fixture: that run goes first), with a short loading each.
set(GABION_SMOKE_CELL ${CMAKE_CURRENT_BINARY_DIR}/smoke/micro_cell/cell.h5)
set(GABION_SMOKE_SET_micro_cc --set cell=${GABION_SMOKE_CELL} --set loading.strain=0.004 --set loading.unload_at_strain=[0.002])
set(GABION_SMOKE_SET_micro_uc --set cell=${GABION_SMOKE_CELL} --set loading.strain=0.004)
set(GABION_SMOKE_SET_micro_uci --set cell=${GABION_SMOKE_CELL} --set velocities_m_s=[8] --set boulder.diameter_m=0.3 --set run.duration_s=0.005)
set(GABION_SMOKE_SET_micro_shear --set cell=${GABION_SMOKE_CELL} --set shear.displacement_m=0.001 --set shear.max_settle_s=0.01)
set(GABION_SMOKE_FIXTURE_micro_cell cell_file)
foreach(lab micro_cc micro_uc micro_uci micro_shear)
  set(GABION_SMOKE_NEEDS_${lab} cell_file)
endforeach()
# The pipeline on the smoke cell, its lab tests as short as their own smoke runs.
set(GABION_SMOKE_SET_pipeline --set cell=${GABION_SMOKE_CELL} --set uci_velocities_m_s=[8]
    --set "stage_settings={\"cc\":[\"loading.strain=0.004\",\"loading.unload_at_strain=[0.002]\"],\"uc\":[\"loading.strain=0.004\"],\"uci\":[\"boulder.diameter_m=0.3\",\"run.duration_s=0.02\"],\"shear\":[\"shear.displacement_m=0.001\",\"shear.max_settle_s=0.01\"]}")
set(GABION_SMOKE_NEEDS_pipeline cell_file)
# The resolved wall needs the pipeline's cell and laws: its check and smoke
# run take the smoke cell and the illustrative laws instead, one cell, a few
# steps, a set settling of a few steps rather than one until at rest (the
# full comparison: docs/resolved.md; the settling to rest: test_resolved).
set(GABION_CHECK_SET_macro_resolved --set cell=${GABION_SMOKE_CELL}
    --set law_file=${PROJECT_SOURCE_DIR}/cases/laws/illustrative.json)
set(GABION_SMOKE_SET_macro_resolved ${GABION_CHECK_SET_macro_resolved} --set structure.cells=[2,1,1]
    --set boulder.diameter_m=0.3 --set resolved.settle.duration_s=0.001 --set resolved.settle.until_at_rest=false
    --set resolved.run.duration_s=0.003 --set hybrid.within_m=[0])
set(GABION_SMOKE_NEEDS_macro_resolved cell_file)
# The hybrid likewise: the struck cell of the smoke cell, a few steps.
set(GABION_CHECK_SET_macro_hybrid --set resolve.cell=${GABION_SMOKE_CELL}
    --set law_file=${PROJECT_SOURCE_DIR}/cases/laws/illustrative.json)
set(GABION_SMOKE_SET_macro_hybrid ${GABION_CHECK_SET_macro_hybrid} --set boulder.diameter_m=0.3
    --set resolve.settle.duration_s=0.001 --set resolve.settle.until_at_rest=false --set resolve.run.duration_s=0.003)
set(GABION_SMOKE_NEEDS_macro_hybrid cell_file)
