"""Tribology of the cam-follower contact (thesis 4.4-4.7): Hertz contact size and
pressure, elastohydrodynamic film thickness, lambda ratio and lubrication regime, the
slide-to-roll ratio, and the modified Benedict-Kelley friction law."""

from camdyn.tribology.benedict_kelley import (
                                   BenedictKelleyFit,
                                   benedict_kelley,
                                   fit_benedict_kelley,
                                   normalized_friction,
)
from camdyn.tribology.film import (
                                   Lubricant,
                                   contact_conditions,
                                   hamrock_dowson_film,
                                   lambda_ratio,
                                   list_lubricants,
                                   load_lubricant,
                                   lubrication_regime,
                                   pan_hamrock_film,
                                   roughness_preset,
)

__all__ = ["Lubricant", "contact_conditions", "hamrock_dowson_film", "pan_hamrock_film", "lambda_ratio",
           "lubrication_regime", "load_lubricant", "list_lubricants", "roughness_preset", "BenedictKelleyFit",
           "benedict_kelley", "fit_benedict_kelley", "normalized_friction"]
