"""Lazy Dask stages over the core, dataset fan-out and schedulers."""
from .stages import (Builder, mirror, compute, load, from_surface, as_key, resident, operators, signal, emd,
                     eemd, eemd_tasks, riesz_potential, monogenic, monogenic_from_potential, hht, save,
                     transform, transform_file, filter_signal, filter_geometry, reconstruct,
                     prominent_features, hks_features, imf_enhancement, manifold_harmonics_filter)
from .scheduling import (SCHEDULERS, MAX_WORKERS, PROGRESS_INTERVAL, SINGLE_THREAD_ENV, worker_count,
                         open_client, compute, ProgressLines)
from .dataset import (FORMATS, SUMMARY_FILES, MAX_ERROR, Failure, Guarded, ItemSummary, output_paths,
                      summary_paths, quality_fields, item_summary, skipped_summary, dataset_graph,
                      write_summary, run_dataset)
