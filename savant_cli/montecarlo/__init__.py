"""Monte Carlo dispersion batches: spec and targets, batch execution and journal, the batch's tables, analysis and outputs."""
