//! Mitsuba 3 emitters added for issue 38, kept apart from `build.rs`: `sunsky` (and the
//! solar position it computes from a date, time and place).

use glam::{Mat4, Vec3};

use super::SceneBuilder;
use crate::Result;
use crate::formats::mitsuba::plugin::Plugin;
use crate::formats::mitsuba::tree::err;
use crate::model::*;

/// The emitter types this module reads.
pub(super) const TYPES: &[&str] = &["sunsky"];

impl<'s> SceneBuilder<'_, 's> {
    /// An emitter of [`TYPES`] (`None`: not one of them).
    pub(super) fn extra_emitter(
        &mut self,
        pl: &Plugin<'s>,
        to_world: Option<Mat4>,
    ) -> Result<Option<Emitter>> {
        Ok(Some(match pl.ty.as_str() {
            "sunsky" => Emitter::SunSky(self.sunsky(pl, to_world.unwrap_or(Mat4::IDENTITY))?),
            _ => return Ok(None),
        }))
    }

    /// Mitsuba 3.9.1's `sunsky`: its parameters, defaults and range checks.
    fn sunsky(&mut self, pl: &Plugin<'s>, to_world: Mat4) -> Result<SunSkyDesc> {
        let turbidity = pl.props.float("turbidity", 3.0)?;
        if !(1.0..=10.0).contains(&turbidity) {
            return Err(err(
                pl.loc(),
                format!("sunsky: turbidity {turbidity} is out of range [1, 10]"),
            ));
        }
        let albedo = self
            .color_value(pl, "albedo", Vec3::splat(0.3), false)?
            .rgb();
        if albedo.min_element() < 0.0 || albedo.max_element() > 1.0 {
            return Err(err(pl.loc(), "sunsky: albedo must be in [0, 1]"));
        }
        let sun_scale = pl.props.float("sun_scale", 1.0)?;
        let sky_scale = pl.props.float("sky_scale", 1.0)?;
        if sun_scale < 0.0 || sky_scale < 0.0 {
            return Err(err(
                pl.loc(),
                "sunsky: sun_scale and sky_scale must be non-negative",
            ));
        }
        let sun_aperture = pl.props.float("sun_aperture", 0.5358)?;
        if !(sun_aperture > 0.0 && sun_aperture < 180.0) {
            return Err(err(
                pl.loc(),
                "sunsky: sun_aperture must be in ]0, 180[ degrees",
            ));
        }
        const TIME_PLACE: [&str; 9] = [
            "latitude",
            "longitude",
            "timezone",
            "year",
            "month",
            "day",
            "hour",
            "minute",
            "second",
        ];
        let sun_direction = match pl.props.vector_opt("sun_direction")? {
            Some(d) => {
                if TIME_PLACE.iter().any(|n| pl.props.has(n)) {
                    return Err(err(
                        pl.loc(),
                        "sunsky: give either 'sun_direction' or the time and place, not both",
                    ));
                }
                let d = d.normalize_or_zero();
                if d == Vec3::ZERO {
                    return Err(err(pl.loc(), "sunsky: sun_direction must be non-zero"));
                }
                d
            }
            None => {
                let int =
                    |name: &str, default: i64| pl.props.int_in(name, default, -100_000, 100_000);
                let when = SolarTime {
                    year: int("year", 2010)?,
                    month: int("month", 7)?,
                    day: int("day", 10)?,
                    hour: pl.props.float("hour", 15.0)? as f64,
                    minute: pl.props.float("minute", 0.0)? as f64,
                    second: pl.props.float("second", 0.0)? as f64,
                };
                let place = SolarPlace {
                    latitude: pl.props.float("latitude", 35.6894)? as f64,
                    longitude: pl.props.float("longitude", 139.6917)? as f64,
                    timezone: pl.props.float("timezone", 9.0)? as f64,
                };
                let (theta, phi) = sun_position(&when, &place);
                let local = Vec3::new(
                    (theta.sin() * phi.cos()) as f32,
                    (theta.sin() * phi.sin()) as f32,
                    theta.cos() as f32,
                );
                to_world.transform_vector3(local).normalize()
            }
        };
        let local = to_world.inverse().transform_vector3(sun_direction);
        if local.z < 0.0 {
            self.ctx.warn(
                pl.loc(),
                "sunsky: the sun is below the horizon: the sun and sky are black (as in Mitsuba)",
            );
        }
        Ok(SunSkyDesc {
            turbidity,
            albedo,
            sun_direction,
            sun_scale,
            sky_scale,
            sun_aperture,
            complex_sun: pl.props.bool("complex_sun", false)?,
            to_world,
        })
    }
}

/// A local date and time.
pub(crate) struct SolarTime {
    pub year: i64,
    pub month: i64,
    pub day: i64,
    pub hour: f64,
    pub minute: f64,
    pub second: f64,
}

/// Where on Earth: degrees (east and north positive) and the time zone's offset in hours.
pub(crate) struct SolarPlace {
    pub latitude: f64,
    pub longitude: f64,
    pub timezone: f64,
}

/// The sun's zenith angle and azimuth (radians) in Mitsuba's sky frame (z up; azimuth
/// measured as Mitsuba's `sunsky` measures it, the solar azimuth from north minus π), by
/// "Computing the solar vector" (Blanco-Muriel, Alarcón-Padilla, López-Moratalla and
/// Lara-Coira, Solar Energy 70(5), 2001): ecliptic, then celestial, then local coordinates,
/// with the parallax correction.
// The paper's constants as published (f32 rounds them as Mitsuba's compiler does).
#[allow(clippy::excessive_precision)]
pub(crate) fn sun_position(t: &SolarTime, p: &SolarPlace) -> (f64, f64) {
    use std::f32::consts::{PI, TAU};
    // In single precision throughout, as Mitsuba computes it: the Julian date near 2.46·10⁶
    // keeps a quarter of a day in f32, which moves the sun by up to a few hundredths of a
    // degree; doing it in f64 would be more accurate and differ from Mitsuba by as much.
    // Days since noon, 1 January 2000, UT; the Julian day by integer arithmetic that
    // truncates as C does (Rust's `/` on integers too).
    let (hour, minute, second) = (t.hour as f32, t.minute as f32, t.second as f32);
    let ut_hours = hour - p.timezone as f32 + (minute + second / 60.0) / 60.0;
    let (year, month, day) = (t.year as i32, t.month as i32, t.day as i32);
    let a = (month - 14) / 12;
    let jd_noon = (1461 * (year + 4800 + a)) / 4 + (367 * (month - 2 - 12 * a)) / 12
        - (3 * ((year + 4900 + a) / 100)) / 4
        + day
        - 32075;
    let jd = jd_noon as f32 - 0.5 + ut_hours / 24.0;
    let n = jd - 2_451_545.0;

    // Ecliptic longitude and obliquity.
    let omega = 2.1429 - 0.0010394594 * n;
    let mean_longitude = 4.895_063 + 0.017202791698 * n;
    let anomaly = 6.24006 + 0.0172019699 * n;
    let lambda = mean_longitude + 0.03341607 * anomaly.sin() + 0.00034894 * (2.0 * anomaly).sin()
        - 0.0001134
        - 0.0000203 * omega.sin();
    let obliquity = 0.4090928 - 6.2140e-9 * n + 0.0000396 * omega.cos();

    // Right ascension and declination.
    let mut ra = (obliquity.cos() * lambda.sin()).atan2(lambda.cos());
    if ra < 0.0 {
        ra += TAU;
    }
    let declination = (obliquity.sin() * lambda.sin()).asin();

    // Local coordinates.
    let gmst = 6.697_424_3 + 0.0657098283 * n + ut_hours;
    let lmst = (gmst * 15.0 + p.longitude as f32).to_radians();
    let lat = (p.latitude as f32).to_radians();
    let hour_angle = lmst - ra;
    let mut zenith =
        (lat.cos() * hour_angle.cos() * declination.cos() + declination.sin() * lat.sin()).acos();
    let mut azimuth =
        (-hour_angle.sin()).atan2(declination.tan() * lat.cos() - lat.sin() * hour_angle.cos());
    if azimuth < 0.0 {
        azimuth += TAU;
    }
    const EARTH_MEAN_RADIUS: f64 = 6371.01; // km
    const ASTRONOMICAL_UNIT: f64 = 149_597_890.0; // km
    zenith += (EARTH_MEAN_RADIUS / ASTRONOMICAL_UNIT) as f32 * zenith.sin();
    (zenith as f64, (azimuth - PI) as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Mitsuba 3.9.1's `sun_direction` for 3 February 2010, 10:30 at 48.1° N, 11.6° E, UTC+1
    /// (`mi.traverse(emitter)['sun_direction']`).
    #[test]
    fn solar_position_matches_mitsuba() {
        let (theta, phi) = sun_position(
            &SolarTime {
                year: 2010,
                month: 2,
                day: 3,
                hour: 10.5,
                minute: 0.0,
                second: 0.0,
            },
            &SolarPlace {
                latitude: 48.1,
                longitude: 11.6,
                timezone: 1.0,
            },
        );
        let d = [
            theta.sin() * phi.cos(),
            theta.sin() * phi.sin(),
            theta.cos(),
        ];
        let want = [0.811472, -0.470079, 0.347186];
        for (g, w) in d.iter().zip(want) {
            assert!((g - w).abs() < 2e-5, "{d:?} vs {want:?}");
        }
    }
}
