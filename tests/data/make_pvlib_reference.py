# ruff: noqa: E501  (verbatim copy of the project script that wrote the reference tables)
"""Regenerate the pvlib reference tables in this folder.

Run with pvlib 0.16.1 (needs pandas, scipy, h5py):
    python make_pvlib_reference.py
It reads ../weather/surfrad-slv16001.dat and writes
    pvlib_ref_alamosa_20160101_1min.csv
    pvlib_ref_suwon_clearsky_5min.csv
The outputs are *computed* reference values (not measurements) so that the
project's own numpy solar-geometry / decomposition / transposition code can be
checked against pvlib without pvlib being a runtime dependency.
"""
from pathlib import Path

import numpy as np
import pandas as pd
import pvlib

HERE = Path(__file__).resolve().parent
WEATHER = HERE.parent / "weather"

# South-facing vertical facade (pvlib azimuth convention: 180 = south).
TILT, AZIM, ALBEDO = 90.0, 180.0, 0.2


def transpositions(sp, dni, ghi, dhi, dni_extra, airmass_rel):
    out = {}
    for model in ("isotropic", "haydavies", "perez"):
        kw = {}
        if model in ("haydavies", "perez"):
            kw["dni_extra"] = dni_extra
        if model == "perez":
            kw["airmass"] = airmass_rel
        poa = pvlib.irradiance.get_total_irradiance(
            TILT, AZIM, sp["apparent_zenith"], sp["azimuth"],
            dni, ghi, dhi, albedo=ALBEDO, model=model, **kw)
        out[f"poa_global_{model}"] = poa["poa_global"]
        out[f"poa_direct_{model}"] = poa["poa_direct"]
        out[f"poa_sky_diffuse_{model}"] = poa["poa_sky_diffuse"]
    out["poa_ground_diffuse"] = poa["poa_ground_diffuse"]
    out["aoi_deg"] = pvlib.irradiance.aoi(TILT, AZIM, sp["apparent_zenith"], sp["azimuth"])
    return pd.DataFrame(out)


def alamosa():
    data, meta = pvlib.iotools.read_surfrad(WEATHER / "surfrad-slv16001.dat")
    lat, lon, alt = meta["latitude"], -meta["longitude"], meta["elevation"]  # file stores west longitude as positive
    t = data.index
    press = data["pressure"] * 100.0  # mbar -> Pa
    sp = pvlib.solarposition.spa_python(t, lat, lon, altitude=alt, pressure=press,
                                        temperature=data["temp_air"])
    eph = pvlib.solarposition.ephemeris(t, lat, lon, pressure=press, temperature=data["temp_air"])
    dni_extra = pvlib.irradiance.get_extra_radiation(t)
    am_rel = pvlib.atmosphere.get_relative_airmass(sp["apparent_zenith"])
    ghi = data["ghi"].clip(lower=0)
    erbs = pvlib.irradiance.erbs(ghi, sp["zenith"], t)
    disc = pvlib.irradiance.disc(ghi, sp["zenith"], t, pressure=press)
    dirint = pvlib.irradiance.dirint(ghi, sp["zenith"], t, pressure=press,
                                     temp_dew=None)
    meas = data[["ghi", "dni", "dhi", "temp_air", "wind_speed", "wind_direction",
                 "relative_humidity", "pressure"]].clip(lower=-50)
    poa = transpositions(sp, data["dni"].clip(lower=0), ghi, data["dhi"].clip(lower=0),
                         dni_extra, am_rel)
    df = pd.DataFrame({
        "meas_" + c: meas[c] for c in meas.columns})
    df["spa_zenith"] = sp["zenith"]
    df["spa_apparent_zenith"] = sp["apparent_zenith"]
    df["spa_azimuth"] = sp["azimuth"]
    df["spa_equation_of_time_min"] = sp["equation_of_time"]
    df["eph_apparent_zenith"] = eph["apparent_zenith"]
    df["eph_azimuth"] = eph["azimuth"]
    df["dni_extra"] = dni_extra
    df["airmass_relative_kastenyoung"] = am_rel
    df["erbs_dni"], df["erbs_dhi"], df["erbs_kt"] = erbs["dni"], erbs["dhi"], erbs["kt"]
    df["disc_dni"] = disc["dni"]
    df["dirint_dni"] = dirint
    df = df.join(poa)
    df.index.name = "time_utc"
    df.round(4).to_csv(HERE / "pvlib_ref_alamosa_20160101_1min.csv")


def suwon():
    # Suwon KMA ASOS 119 (approx.): 37.2723 N, 126.9853 E, 34 m; KST = UTC+9
    lat, lon, alt = 37.2723, 126.9853, 34.0
    loc = pvlib.location.Location(lat, lon, tz="Asia/Seoul", altitude=alt)
    days = ["2016-12-21", "2017-01-15"]
    t = pd.DatetimeIndex(np.concatenate([
        pd.date_range(d, periods=288, freq="5min", tz="Asia/Seoul").values for d in days])).tz_localize("UTC").tz_convert("Asia/Seoul")
    sp = pvlib.solarposition.spa_python(t, lat, lon, altitude=alt)
    eph = pvlib.solarposition.ephemeris(t, lat, lon)
    cs = loc.get_clearsky(t, model="ineichen", solar_position=sp)
    dni_extra = pvlib.irradiance.get_extra_radiation(t)
    am_rel = pvlib.atmosphere.get_relative_airmass(sp["apparent_zenith"])
    erbs = pvlib.irradiance.erbs(cs["ghi"], sp["zenith"], t)
    poa = transpositions(sp, cs["dni"], cs["ghi"], cs["dhi"], dni_extra, am_rel)
    df = pd.DataFrame({
        "spa_zenith": sp["zenith"], "spa_apparent_zenith": sp["apparent_zenith"],
        "spa_azimuth": sp["azimuth"], "spa_elevation": sp["elevation"],
        "eph_apparent_zenith": eph["apparent_zenith"], "eph_azimuth": eph["azimuth"],
        "dni_extra": dni_extra, "airmass_relative_kastenyoung": am_rel,
        "cs_ineichen_ghi": cs["ghi"], "cs_ineichen_dni": cs["dni"], "cs_ineichen_dhi": cs["dhi"],
        "erbs_dni_from_cs_ghi": erbs["dni"], "erbs_dhi_from_cs_ghi": erbs["dhi"],
    }).join(poa)
    df.index.name = "time_kst"
    df.round(4).to_csv(HERE / "pvlib_ref_suwon_clearsky_5min.csv")


if __name__ == "__main__":
    print("pvlib", pvlib.__version__)
    alamosa()
    suwon()
