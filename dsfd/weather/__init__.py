"""Weather at the edge: file readers, the :class:`WeatherSeries` container and its time axis.

Readers return UTC interval midpoints; :func:`resample` gives model-step midpoints
(docs/model.md#time-convention); :func:`shift_to_site` replays foreign weather at the same local
solar time.
"""

from dsfd.weather.daily import read_kma_daily
from dsfd.weather.readers import (
    BUNDLED_WEATHER,
    bundled_weather,
    read_epw,
    read_rmis,
    read_surfrad,
    read_tmy3,
    read_weather,
)
from dsfd.weather.series import (
    CHANNELS,
    MAX_FILL_SAMPLES,
    WeatherSeries,
    fill_short_gaps,
    interpolate,
    resample,
    shift_to_site,
)

__all__ = [
    "BUNDLED_WEATHER",
    "CHANNELS",
    "MAX_FILL_SAMPLES",
    "WeatherSeries",
    "bundled_weather",
    "fill_short_gaps",
    "interpolate",
    "read_epw",
    "read_kma_daily",
    "read_rmis",
    "read_surfrad",
    "read_tmy3",
    "read_weather",
    "resample",
    "shift_to_site",
]
