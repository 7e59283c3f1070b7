"""Execution infrastructure below the pipeline, the studies and the verification manual: the dask client and task
mapping (:mod:`fivid.execution.cluster`), the output-folder lock (:mod:`fivid.execution.lock`) and the memory
estimates checked before work starts (:mod:`fivid.execution.resources`). Imports no dask until tasks run."""
