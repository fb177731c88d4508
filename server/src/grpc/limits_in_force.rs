//! The limits and the safety distance a run keeps: the request's, then its robot's record's, then the server's
//! default profile (`[defaults.limits]`, `[defaults] margin_m`). On the wire a field left 0 is not set and a
//! negative one means none, explicitly; the run reports what it keeps in a `v1::LimitsInForce`.

use dmp_proto::v1;
use tracing::info;

use crate::config::Defaults;
use crate::error::ServerError;

/// Where a field's value came from, in the order that they win.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum Source {
    Request,
    Record,
    Default,
}

impl Source {
    const ALL: [Source; 3] = [Source::Request, Source::Record, Source::Default];

    fn name(self) -> &'static str {
        match self {
            Source::Request => "request",
            Source::Record => "robot record",
            Source::Default => "server default",
        }
    }
}

/// What a run keeps, resolved.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct InForce {
    /// The engine's limits (0: no limit on a field).
    pub(super) limits: dmp::Limits,
    /// The safety distance from every obstacle, metres (0: none).
    pub(super) margin: f64,
    /// What is reported on the plan and on the first segment of a stream.
    pub(super) reported: v1::LimitsInForce,
}

/// The six fields of `l` by their name in `v1::Limits`.
fn fields(l: &v1::Limits) -> [(&'static str, f64); 6] {
    [
        ("max_speed", l.max_speed),
        ("max_acceleration", l.max_acceleration),
        ("max_jerk", l.max_jerk),
        ("max_angular_speed", l.max_angular_speed),
        ("max_angular_acceleration", l.max_angular_acceleration),
        ("max_angular_jerk", l.max_angular_jerk),
    ]
}

/// The wire's limits of six values in the order of [`fields`].
fn limits_of(v: [f64; 6]) -> v1::Limits {
    v1::Limits {
        max_speed: v[0],
        max_acceleration: v[1],
        max_jerk: v[2],
        max_angular_speed: v[3],
        max_angular_acceleration: v[4],
        max_angular_jerk: v[5],
    }
}

/// A robot record's or a request's limits, each field finite (0: not set, negative: none); the error names
/// `{prefix}.{field}`.
pub(super) fn check_limits(l: &v1::Limits, prefix: &str) -> Result<(), ServerError> {
    for (field, v) in fields(l) {
        if !v.is_finite() {
            return Err(ServerError::invalid(
                format!("{prefix}.{field}"),
                format!("must be a finite number (0: not set, negative: no limit), not {v}"),
            ));
        }
    }
    Ok(())
}

/// A robot record's or a request's safety distance: finite, at most `dmp::ranges::MARGIN_M` (0: not set,
/// negative: none); the error names `field`.
pub(super) fn check_margin(margin: f64, field: &str) -> Result<(), ServerError> {
    let max = *dmp::ranges::MARGIN_M.end();
    if !(margin.is_finite() && margin <= max) {
        return Err(ServerError::invalid(
            field,
            format!(
                "must be a finite number of metres, at most {max} (0: not set, negative: none), not {margin}"
            ),
        ));
    }
    Ok(())
}

/// Resolves the limits and the safety distance of a run of `robot` from its request (`spec`, whose fields are
/// named under `prefix`), its robot's `record` and the server's `defaults`. A negative field of the request or the
/// record (no limit, explicitly) is logged at info, naming the robot and the fields.
pub(super) fn resolve(
    robot: &str,
    spec: &v1::MotionSpec,
    record: &v1::RobotRecord,
    defaults: &Defaults,
    prefix: &str,
) -> Result<InForce, ServerError> {
    let requested = spec.limits.unwrap_or_default();
    check_limits(&requested, &format!("{prefix}.limits"))?;
    check_margin(spec.margin, &format!("{prefix}.margin"))?;
    let stored = record.limits.unwrap_or_default();
    // Checked when it was put; a record stored before a rule existed is not the request's fault.
    check_limits(&stored, "limits")
        .and_then(|()| check_margin(record.margin, "margin"))
        .map_err(|e| ServerError::Internal(format!("the stored record of robot `{robot}`: {e}")))?;
    let (requested, stored, default) = (fields(&requested), fields(&stored), defaults.limits.fields());
    let mut values = [0.0; 6];
    let mut sources = Vec::new();
    let mut unlimited = Vec::new();
    let mut turned_off = Vec::new();
    for i in 0..6 {
        let (field, _) = requested[i];
        let Some((source, v)) = [(Source::Request, requested[i].1), (Source::Record, stored[i].1)]
            .into_iter()
            .chain([(Source::Default, default[i].1)])
            .find(|(_, v)| *v != 0.0)
        else {
            continue;
        };
        sources.push(source);
        if v > 0.0 {
            values[i] = v;
        } else {
            unlimited.push(field.to_owned());
            if source != Source::Default {
                turned_off.push(field);
            }
        }
    }
    let margin = [(Source::Request, spec.margin), (Source::Record, record.margin)]
        .into_iter()
        .chain([(Source::Default, defaults.margin_m)])
        .find(|(_, m)| *m != 0.0);
    if let Some((source, m)) = margin {
        sources.push(source);
        if m < 0.0 && source != Source::Default {
            turned_off.push("margin");
        }
    }
    let margin = margin.map_or(0.0, |(_, m)| m.max(0.0));
    if !turned_off.is_empty() {
        info!(robot = %robot, fields = ?turned_off, "limits off on request: the run keeps none on these fields");
    }
    let limits = limits_of(values);
    let reported = v1::LimitsInForce { limits: Some(limits), profile: profile(&sources), unlimited, margin };
    let limits = dmp_proto::limits::limits_from_proto(Some(&limits))
        .map_err(|e| ServerError::from(e).within(&format!("{prefix}.limits")))?;
    Ok(InForce { limits, margin, reported })
}

/// The sources, once each in the order that they win, joined for a person: "request + server default".
fn profile(sources: &[Source]) -> String {
    let names: Vec<&str> = Source::ALL.iter().filter(|s| sources.contains(s)).map(|s| s.name()).collect();
    if names.is_empty() { "none".to_owned() } else { names.join(" + ") }
}

/// What a group keeps: the tightest of its members' limits field by field, the largest of their safety distances;
/// the profile names every member's sources.
pub(super) fn group(members: &[&InForce]) -> InForce {
    let limits = members.iter().fold(dmp::Limits::NONE, |a, m| dmp_proto::limits::tightest(&a, &m.limits));
    let margin = members.iter().map(|m| m.margin).fold(0.0, f64::max);
    let sources: Vec<Source> = Source::ALL
        .into_iter()
        .filter(|s| members.iter().any(|m| m.reported.profile.contains(s.name())))
        .collect();
    let wire = dmp_proto::limits::limits_to_proto(&limits);
    let unlimited = fields(&wire).iter().filter(|(_, v)| *v == 0.0).map(|(f, _)| (*f).to_owned()).collect();
    let reported = v1::LimitsInForce { limits: Some(wire), profile: profile(&sources), unlimited, margin };
    InForce { limits, margin, reported }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::default_limits::DefaultLimits;

    fn spec(limits: Option<v1::Limits>, margin: f64) -> v1::MotionSpec {
        v1::MotionSpec { limits, margin, ..Default::default() }
    }

    #[test]
    fn the_request_then_the_record_then_the_default_and_negative_is_none() {
        let defaults = Defaults::default();
        // Nothing set: the default profile, whole.
        let r = resolve("r", &spec(None, 0.0), &v1::RobotRecord::default(), &defaults, "motion").unwrap();
        assert_eq!(r.reported.profile, "server default");
        assert_eq!(r.limits.max_speed, 1.0);
        assert_eq!(r.limits.max_angular_jerk, 100.0);
        assert!(r.reported.unlimited.is_empty());
        assert_eq!((r.margin, r.reported.margin), (0.01, 0.01));

        let record = v1::RobotRecord {
            limits: Some(v1::Limits { max_speed: 0.5, max_jerk: -1.0, ..Default::default() }),
            margin: 0.05,
            ..Default::default()
        };
        let asked = v1::Limits { max_speed: 0.25, max_acceleration: -1.0, ..Default::default() };
        let r = resolve("r", &spec(Some(asked), -1.0), &record, &defaults, "motion").unwrap();
        assert_eq!(r.reported.profile, "request + robot record + server default");
        assert_eq!((r.limits.max_speed, r.limits.max_acceleration, r.limits.max_jerk), (0.25, 0.0, 0.0));
        assert_eq!(r.limits.max_angular_speed, 2.0);
        assert_eq!(r.reported.unlimited, ["max_acceleration", "max_jerk"]);
        let wire = r.reported.limits.unwrap();
        assert_eq!((wire.max_speed, wire.max_acceleration), (0.25, 0.0));
        assert_eq!(r.margin, 0.0, "the request's negative margin is none");

        let r = resolve("r", &spec(None, 0.0), &record, &defaults, "motion").unwrap();
        assert_eq!(r.margin, 0.05, "the record's margin");

        // A default field set negative: no default for it.
        let open = Defaults {
            limits: DefaultLimits { max_jerk: -1.0, max_angular_jerk: -1.0, ..DefaultLimits::default() },
            margin_m: -1.0,
            ..Defaults::default()
        };
        let r = resolve("r", &spec(None, 0.0), &v1::RobotRecord::default(), &open, "motion").unwrap();
        assert_eq!(r.reported.unlimited, ["max_jerk", "max_angular_jerk"]);
        assert_eq!(r.margin, 0.0);
    }

    #[test]
    fn everything_negative_is_the_unlimited_engine() {
        let all = v1::Limits {
            max_speed: -1.0,
            max_acceleration: -1.0,
            max_jerk: -1.0,
            max_angular_speed: -1.0,
            max_angular_acceleration: -1.0,
            max_angular_jerk: -1.0,
        };
        let r = resolve("r", &spec(Some(all), -1.0), &v1::RobotRecord::default(), &Defaults::default(), "m")
            .unwrap();
        assert_eq!(r.limits, dmp::Limits::NONE);
        assert_eq!((r.margin, r.reported.profile.as_str()), (0.0, "request"));
        assert_eq!(r.reported.unlimited.len(), 6);
    }

    #[test]
    fn bad_fields_are_refused_by_name() {
        let d = Defaults::default();
        let nan = v1::Limits { max_jerk: f64::NAN, ..Default::default() };
        let e = resolve("r", &spec(Some(nan), 0.0), &v1::RobotRecord::default(), &d, "motion").unwrap_err();
        assert!(e.to_string().starts_with("motion.limits.max_jerk:"), "{e}");
        let e =
            resolve("r", &spec(None, f64::INFINITY), &v1::RobotRecord::default(), &d, "motion").unwrap_err();
        assert!(e.to_string().starts_with("motion.margin:"), "{e}");
        let e = resolve("r", &spec(None, 1e4), &v1::RobotRecord::default(), &d, "motion").unwrap_err();
        assert!(e.to_string().starts_with("motion.margin:"), "{e}");
    }

    #[test]
    fn a_group_keeps_the_tightest_of_its_members() {
        let d = Defaults::default();
        let a = resolve("a", &spec(None, 0.0), &v1::RobotRecord::default(), &d, "m").unwrap();
        let slow = v1::Limits { max_speed: 0.5, max_jerk: -1.0, ..Default::default() };
        let b = resolve("b", &spec(Some(slow), 0.2), &v1::RobotRecord::default(), &d, "m").unwrap();
        let g = group(&[&a, &b]);
        assert_eq!((g.limits.max_speed, g.limits.max_jerk), (0.5, 50.0));
        assert_eq!(g.margin, 0.2);
        assert_eq!(g.reported.profile, "request + server default");
        assert!(g.reported.unlimited.is_empty());
    }
}
