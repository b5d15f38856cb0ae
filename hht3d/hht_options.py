"""The settings of one HHT: EMD's, the Riesz transform's and the ensemble's, as one record or flat names.

:class:`HHTOptions` holds one record per part (:data:`PARTS`); flat settings
are routed by name to the record that declares them (the names are
disjoint), so ``hht(surface, s, max_imfs=3, tol=1e-6)`` sets one EMD and one
Riesz setting.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Any

from .decomposition.options import EMD_DEFAULTS, EMDOptions, EnsembleOptions
from .errors import HHT3DDeprecationWarning, InputError, shown
from .records import Record, route
from .spectral.options import RIESZ_DEFAULTS, RieszOptions

__all__ = ["HHTOptions", "PARTS", "hht_settings"]

#: The parts of :class:`HHTOptions`, by the record each holds.
PARTS: dict[str, type[Record]] = {"emd": EMDOptions, "riesz": RieszOptions, "ensemble": EnsembleOptions}


@dataclass(frozen=True)
class HHTOptions:
    """The settings of one HHT: EMD's, the Riesz transform's and, for ensemble EMD, the ensemble's.

    ``ensemble=None`` decomposes by plain EMD.  :meth:`of` routes flat
    settings by name to the record that declares them (their names are
    disjoint), so ``HHTOptions.of(max_imfs=3, tol=1e-6)`` sets one EMD and
    one Riesz setting.
    """

    emd: EMDOptions = EMD_DEFAULTS
    riesz: RieszOptions = RIESZ_DEFAULTS
    ensemble: EnsembleOptions | None = None

    @classmethod
    def of(cls, value: Any = None, /, **overrides: Any) -> "HHTOptions":
        """From ``None``, an :class:`HHTOptions` or a dict of parts (``{"emd": {...}, "riesz": ...}``)
        and/or flat settings, with flat ``overrides``; an ensemble setting turns ensemble EMD on.

        Raises
        ------
        InputError
            A setting no record declares (with the closest name), or an invalid value.
        """
        if value is None or isinstance(value, cls):
            base, flat = value or cls(), {}
        elif isinstance(value, dict):
            parts: dict[str, Any] = {
                k: None if k == "ensemble" and v is None else PARTS[k].of(v) for k, v in value.items() if k in PARTS
            }
            base = cls(**parts)
            flat = {k: v for k, v in value.items() if k not in PARTS}
        else:
            raise InputError(f"HHT options must be an HHTOptions or a dict; got {shown(value)}")
        emd, riesz, ensemble = route({**flat, **overrides}, *PARTS.values())
        return cls(
            EMDOptions.of(base.emd, **emd),
            RieszOptions.of(base.riesz, **riesz),
            None if base.ensemble is None and not ensemble else EnsembleOptions.of(base.ensemble, **ensemble),
        )


def hht_settings(options: HHTOptions | dict | None, overrides: dict, function: str) -> HHTOptions:
    """:meth:`HHTOptions.of`, accepting for one release the former keywords ``emd=``, ``riesz=`` and
    ``ensemble=`` of ``function`` with a DeprecationWarning."""
    former = {k: overrides.pop(k) for k in PARTS if k in overrides}
    if former:
        warnings.warn(
            f"{function}({'=, '.join(former)}=) is deprecated: pass the settings by name "
            "(max_imfs=3, tol=1e-6) or as options",
            HHT3DDeprecationWarning,
            stacklevel=3,
        )
        base = HHTOptions.of(options)
        options = {**{k: getattr(base, k) for k in PARTS}, **former}
    return HHTOptions.of(options, **overrides)
