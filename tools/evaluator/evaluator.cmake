# Targets of the mesh evaluator (owned by the evaluator work; included from the root).
