"""Write the two tiny SYNTHETIC weather files used by tests/weather/test_readers.py.

    python tests/data/make_tiny_format_samples.py

The rows follow the published EPW (EnergyPlus "Auxiliary Programs", weather file format)
and NSRDB TMY3 (NREL/TP-581-43156 user's manual) layouts, but every value is made up:
irradiance is a smooth clear-sky-like function of the sun position at each hour's
midpoint (hour-ending stamps in local standard time), so a reader that gets the time
convention right puts the irradiance centroid at solar noon. A few values are set to the
formats' missing codes on purpose. Not real weather; do not use for anything else.
"""

from __future__ import annotations

import calendar
from pathlib import Path

import numpy as np

from dsfd.physics.solar import solar_position

HERE = Path(__file__).resolve().parent


def synthetic_hour(unix_mid: float, lat: float, lon: float) -> tuple[float, float, float]:
    cos_z = max(np.cos(np.radians(solar_position(unix_mid, lat, lon).zenith_deg)), 0.0)
    dni = 850.0 * cos_z**0.3 if cos_z > 0.02 else 0.0
    dhi = 90.0 * cos_z**0.6
    return round(dni * cos_z + dhi), round(dni), round(dhi)


def write_epw() -> None:
    lat, lon, tz, elev = 37.27, 126.99, 9.0, 34.0
    lines = [
        f"LOCATION,Synthetic Suwon,GG,KOR,dsfd synthetic sample,999999,{lat},{lon},{tz},{elev}",
        "DESIGN CONDITIONS,0",
        "TYPICAL/EXTREME PERIODS,0",
        "GROUND TEMPERATURES,0",
        "HOLIDAYS/DAYLIGHT SAVINGS,No,0,0,0",
        "COMMENTS 1,SYNTHETIC values written by tests/data/make_tiny_format_samples.py",
        "COMMENTS 2,Not real weather: format test only",
        "DATA PERIODS,1,1,Data,Sunday, 1/ 1, 1/ 2",
    ]
    for k in range(30):
        day, hour = 1 + k // 24, 1 + k % 24
        mid = calendar.timegm((2017, 1, day, 0, 0, 0)) + 3600 * hour - 1800 - tz * 3600
        ghi, dni, dhi = synthetic_hour(mid, lat, lon)
        t_air = -3.0 + 4.0 * np.sin(2 * np.pi * (hour - 9) / 24)
        wind_dir = (350 + 10 * k) % 360  # veers through north
        if k == 12:  # missing GHI at 13:00 (hour 12-13)
            ghi = 9999
        t_text = "99.9" if k == 5 else f"{t_air:.1f}"
        fields = [2017, 1, day, hour, 60, "?9?9?9?9E0?9?9?9?9?9?9?9?9?9?9?9?9?9?9*9*9?9?9?9",
                  t_text, f"{t_air - 6:.1f}", 60, 102100, 0, 1415, 250, ghi, dni, dhi,
                  0, 0, 0, 0, wind_dir, 2.5, 5, 3, 20.0, 77777, 9, 999999999, 5, 0.08, 0,
                  88, 0.2, 0.0, 0.0]
        lines.append(",".join(str(f) for f in fields))
    (HERE / "tiny_format_sample_synthetic.epw").write_text("\n".join(lines) + "\n")


TMY3_HEADER = (
    "Date (MM/DD/YYYY),Time (HH:MM),ETR (W/m^2),ETRN (W/m^2),GHI (W/m^2),GHI source,"
    "GHI uncert (%),DNI (W/m^2),DNI source,DNI uncert (%),DHI (W/m^2),DHI source,"
    "DHI uncert (%),GH illum (lx),GH illum source,Global illum uncert (%),DN illum (lx),"
    "DN illum source,DN illum uncert (%),DH illum (lx),DH illum source,DH illum uncert (%),"
    "Zenith lum (cd/m^2),Zenith lum source,Zenith lum uncert (%),TotCld (tenths),"
    "TotCld source,TotCld uncert (code),OpqCld (tenths),OpqCld source,OpqCld uncert (code),"
    "Dry-bulb (C),Dry-bulb source,Dry-bulb uncert (code),Dew-point (C),Dew-point source,"
    "Dew-point uncert (code),RHum (%),RHum source,RHum uncert (code),Pressure (mbar),"
    "Pressure source,Pressure uncert (code),Wdir (degrees),Wdir source,Wdir uncert (code),"
    "Wspd (m/s),Wspd source,Wspd uncert (code),Hvis (m),Hvis source,Hvis uncert (code),"
    "CeilHgt (m),CeilHgt source,CeilHgt uncert (code),Pwat (cm),Pwat source,"
    "Pwat uncert (code),AOD (unitless),AOD source,AOD uncert (code),Alb (unitless),"
    "Alb source,Alb uncert (code),Lprecip depth (mm),Lprecip quantity (hr),Lprecip source,"
    "Lprecip uncert (code)"
)


def write_tmy3() -> None:
    lat, lon, tz, elev = 39.742, -105.18, -7.0, 1829
    lines = [f'999999,"DSFD SYNTHETIC SAMPLE",CO,{tz},{lat},{lon},{elev}', TMY3_HEADER]
    # 31 Jan from "1991" and 1 Feb from "1988": months of a typical year come from
    # different source years, so the raw stamps go backwards in time.
    for k in range(30):
        month, day, year = (1, 31, 1991) if k < 24 else (2, 1, 1988)
        hour = 1 + k % 24
        mid = calendar.timegm((1991, month, day, 0, 0, 0)) + 3600 * hour - 1800 - tz * 3600
        ghi, dni, dhi = synthetic_hour(mid, lat, lon)
        t_air = 2.0 + 5.0 * np.sin(2 * np.pi * (hour - 9) / 24)
        pressure = -9900 if k == 20 else 815
        fields = [f"{month:02d}/{day:02d}/{year}", f"{hour:02d}:00", 0, 1415,
                  ghi, 2, 8, dni, 2, 12, dhi, 2, 8, 0, 2, 8, 0, 2, 12, 0, 2, 8, 0, 2, 12,
                  2, "E", 9, 1, "E", 9, f"{t_air:.1f}", "A", 7, f"{t_air - 8:.1f}", "A", 7,
                  55, "A", 7, pressure, "A", 7, 270, "A", 7, 3.1, "A", 7, 16000, "A", 7,
                  77777, "A", 7, 0.4, "E", 8, 0.05, "F", 8, 0.3, "F", 8, 0, 1, "D", 9]
        lines.append(",".join(str(f) for f in fields))
    (HERE / "tiny_format_sample_synthetic_tmy3.csv").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    write_epw()
    write_tmy3()
