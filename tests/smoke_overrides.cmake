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
