//! The EXR header of a render: its figures and settings as `illum.*` attributes.

use super::ImageMetadata;
use crate::render::{RenderOutput, RenderSettings};

/// The EXR header of a render: what `illum render`, `illum compare`, `illum view` and Python
/// write alike.
pub fn image_metadata(
    out: &RenderOutput,
    settings: &RenderSettings,
    device: &str,
) -> ImageMetadata {
    let s = &out.stats;
    let it = &settings.integrator;
    let last = out.passes.last().cloned().unwrap_or_default();
    let mut extra = vec![
        ("illum.trace".to_string(), s.trace.to_string()),
        ("illum.integrator".into(), it.name().into()),
    ];
    extra.extend(
        it.header()
            .into_iter()
            .map(|(k, v)| (format!("illum.{k}"), v)),
    );
    extra.extend([
        (
            "illum.nonFiniteSamples".into(),
            s.non_finite_samples.to_string(),
        ),
        (
            "illum.deviceSeconds".into(),
            format!("{:.6}", s.device_seconds),
        ),
    ]);
    if let Some(b) = s.bands {
        extra.push((
            "illum.bands".into(),
            format!("{} of {} rows", b.count, b.rows),
        ));
    }
    if let Some(e) = last.estimated_relmse {
        extra.push(("illum.estimatedRelMSE".into(), format!("{e:.6e}")));
    }
    for (name, value) in &s.integrator {
        extra.push((format!("illum.{name}"), value.clone()));
    }
    if let Some(a) = settings.adaptive {
        match a.target {
            crate::render::adaptive::Target::Threshold(t) => {
                extra.push(("illum.noiseThreshold".into(), t.to_string()))
            }
            crate::render::adaptive::Target::Mean(n) => {
                extra.push(("illum.adaptiveMeanSpp".into(), n.to_string()))
            }
        }
        extra.push(("illum.minSpp".into(), a.min_spp.to_string()));
    }
    if let Some(c) = settings.clamp {
        extra.push(("illum.fireflyClamp".into(), format!("{c} (biased)")));
        extra.push(("illum.clampedSamples".into(), s.clamped_samples.to_string()));
    }
    if let Some(e) = last.error {
        extra.push(("illum.relMSE".into(), format!("{:.6e}", e.relmse)));
        extra.push(("illum.RMSE".into(), format!("{:.6e}", e.rmse)));
        extra.push(("illum.MAE".into(), format!("{:.6e}", e.mae)));
    }
    if s.interrupted {
        extra.push(("illum.interrupted".into(), "true".into()));
        extra.push(("illum.sppRequested".into(), settings.spp.to_string()));
    }
    ImageMetadata {
        spp: s.spp,
        render_seconds: s.render_seconds,
        setup_seconds: s.setup_seconds,
        device: device.to_string(),
        seed: settings.seed,
        extra,
    }
}
