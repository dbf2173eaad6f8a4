"""The names of what ``ogcp plot`` draws, in a module that imports nothing.

``ogcp plot --help`` lists them without loading numpy and the suite's records;
:mod:`ogcp.benchmarks.plots.report` pairs each figure name with its builder.
"""

#: File stems of the figures, in the order they are drawn (each builder is named after its stem).
FIGURE_NAMES = (
    "fig3_grasps",
    "fig4_q1_histograms",
    "fig5_search_tree",
    "fig6_states_per_level",
    "fig7_iterations_f",
    "fig8_wastar_tradeoff",
    "sim_q1_vs_resistance",
    "sim_fidelity",
    "sim_survival",
    "sim_protocol",
    "fig10_hand_grasps",
    "sim_grasps",
)
#: File stem of the time table (Fig. 9).
TABLE = "fig9_times"
#: What ``--only`` selects from: the figures, then the table.
NAMES = (*FIGURE_NAMES, TABLE)
