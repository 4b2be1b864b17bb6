"""`chronav evaluate`: a study of planners across scenes and seeds (sweep, pool, table, statistics, figures, report)."""
