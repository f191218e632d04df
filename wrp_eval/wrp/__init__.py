"""The wind-resistance-path stage (see README.md in this folder): the paper's interval optimisation
(Sec. 4.2, Alg. 3 and 4; ISWRP Def. 4.2, SWRP Def. 4.3) of a planned path against a trained surrogate, and the
robustness evaluation of the initial path, ISWRP and SWRP under the same wind realisations.
"""
