"""Figures, rendering and the interactive HTML viewer."""
from .figures import (IMF_CMAP, FREQUENCY_CMAP, AMPLITUDE_CMAP, font_points, draw_colorbar, draw_image,
                      field_figure, save_figure, render_png, hht_figure, spectrum_figure, write_figures)
from .viewer import (VERTEX_BUDGET, CLUSTER_ABOVE, PAGE_BUDGETS, PERCENTILES, SHAPE, Shown, shown_copy,
                     color_limits, write_page, result_html, surfaces_html, read_fields, file_html)
