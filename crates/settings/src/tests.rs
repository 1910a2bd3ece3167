use super::*;

#[test]
fn defaults_validate() {
    assert_eq!(RenderSettings::default().validate(), Ok(()));
}

#[test]
fn counts_out_of_range_name_their_setting() {
    let s = RenderSettings {
        spp: 0,
        ..RenderSettings::default()
    };
    let e = s.validate().unwrap_err();
    assert_eq!(e.setting(), Setting::Spp);
    assert_eq!(e.to_string(), "0 is outside [1, 4294967295]");
    let s = RenderSettings {
        pixel_table_rays: Some(limits::MAX_PIXEL_TABLE_RAYS + 1),
        ..RenderSettings::default()
    };
    assert_eq!(s.validate().unwrap_err().setting(), Setting::PixelTableRays);
}

#[test]
fn light_tracing_needs_jittered_pixels() {
    let s = RenderSettings {
        light_tracing: true,
        ..RenderSettings::default()
    };
    assert_eq!(s.validate(), Ok(()));
    let s = RenderSettings {
        pixel_jitter: false,
        ..s
    };
    assert_eq!(s.validate(), Err(SettingsError::LightTracingWithoutJitter));
    assert_eq!(
        SettingsError::LightTracingWithoutJitter.setting(),
        Setting::LightTracing
    );
}

#[test]
fn adaptive_radius_goes_with_light_tracing() {
    let s = RenderSettings {
        adaptive_radius: true,
        light_tracing: true,
        ..RenderSettings::default()
    };
    assert_eq!(s.validate(), Ok(()));
}

#[test]
fn radius_errors_are_typed() {
    assert_eq!(check_radius(-1.0), Err(RadiusError::NotPositive(-1.0)));
    assert_eq!(check_radius(1e-20), Err(RadiusError::BelowMinimum(1e-20)));
    assert!(
        check_radius(1e-20)
            .unwrap_err()
            .to_string()
            .contains("smallest usable")
    );
}

/// The threshold radius and the clamp each have one source, the settings' own fields: the
/// heuristic is built from them, and nothing is written back into the mode.
#[test]
fn the_heuristic_is_built_from_one_source_each() {
    let mut s = RenderSettings {
        mode: "threshold".parse().unwrap(),
        threshold_radius: 0.5,
        ..RenderSettings::default()
    };
    assert_eq!(s.validate(), Ok(()));
    assert_eq!(s.heuristic(), Some(Heuristic::Threshold { radius: 0.5 }));
    // f32 precision, as a scene file gives it.
    s.threshold_radius = 0.7;
    assert_eq!(
        s.heuristic(),
        Some(Heuristic::Threshold {
            radius: 0.7f32 as f64
        })
    );
    s.threshold_radius = f32::MIN_POSITIVE / 2.0;
    assert_eq!(
        s.validate().unwrap_err().setting(),
        Setting::ThresholdRadius
    );
    s.mode = Mode::Path;
    assert_eq!(s.heuristic(), None);
}

/// The footprint model's clamp is computed and reported, and the request stays as given.
#[test]
fn clamp_is_computed_not_written_back() {
    let mut s = RenderSettings {
        mode: Mode::parse("optimal").unwrap(),
        ..RenderSettings::default()
    };
    let clamp = s.weight_clamp();
    assert!(!clamp.requested && clamp.footprint && clamp.effective());
    assert_eq!(
        s.heuristic(),
        Some(Heuristic::Optimal {
            clamp_weights: true
        })
    );
    assert!(!s.clamp_weights);
    s.pixel_jitter = false;
    assert!(!s.weight_clamp().effective());
    assert_eq!(
        s.heuristic(),
        Some(Heuristic::Optimal {
            clamp_weights: false
        })
    );
    s.clamp_weights = true;
    assert!(s.weight_clamp().requested);
    assert_eq!(
        s.heuristic(),
        Some(Heuristic::Optimal {
            clamp_weights: true
        })
    );
    let r = s.record(0.01, false, None);
    assert!(r.clamp_weights && r.clamp_weights_requested);
}

#[test]
fn record_feeds_the_header() {
    let r = RenderSettings::default().record(0.25, true, Some(0.01));
    let h = r.header_attributes();
    assert_eq!(h[0], ("mode", "optimal-path".to_string()));
    assert!(h.contains(&("radius_source", "given".to_string())));
    assert!(h.contains(&("radius_m", "0.25".to_string())));
    assert!(h.contains(&("radius_px", "25".to_string())));
}

#[test]
fn radius_in_pixels_parses_applies_and_validates() {
    assert_eq!(RadiusSpec::parse("1.5px"), Ok(RadiusSpec::Pixels(1.5)));
    assert_eq!(RadiusSpec::parse(" 0.01 "), Ok(RadiusSpec::Metres(0.01)));
    assert_eq!(RadiusSpec::parse("0.01m"), Ok(RadiusSpec::Metres(0.01)));
    for bad in ["", "px", "1 pixel", "1e40 pixels", "abc"] {
        assert!(RadiusSpec::parse(bad).is_err(), "{bad}");
    }
    // Numbers out of range parse; their range is checked as written (`RadiusInput::spec`).
    for (text, message) in [
        (
            "-1px",
            "-1 px: the radius must be positive, a number of pixel footprints in (0, 1000]",
        ),
        (
            "1e40px",
            "1e40 px: the radius must be positive, a number of pixel footprints in (0, 1000]",
        ),
        ("nanpx", "NaN px: the radius must be positive"),
        (
            "1e-50px",
            "1e-50 px is below the smallest normal single-precision number",
        ),
        ("0", "0 must be a finite number > 0 (metres)"),
        ("-0.5m", "-0.5 must be a finite number > 0 (metres)"),
        (
            "1e-19",
            "1e-19 m is below the smallest usable merge radius 1e-18 m",
        ),
    ] {
        let e = RadiusInput::Text(text.into()).spec().unwrap_err();
        assert_eq!(e.setting(), Setting::Radius);
        assert!(e.to_string().starts_with(message), "{text}: {e}");
    }
    let mut s = RenderSettings::default();
    RadiusSpec::Metres(0.02).apply(&mut s);
    RadiusSpec::Pixels(2.0).apply(&mut s);
    assert_eq!((s.radius, s.radius_px), (None, Some(2.0)));
    assert!(s.validate().is_ok());
    s.radius_px = Some(MAX_RADIUS_PX * 2.0);
    assert_eq!(
        s.validate(),
        Err(SettingsError::RadiusPx((MAX_RADIUS_PX * 2.0).into()))
    );
    // Metres set in code over the default's pixels: valid, and the metres are in force (the
    // renderer's `resolve_radius`, tested in bdpm-integrator).
    s.radius_px = Some(1.0);
    s.radius = Some(0.01);
    assert!(s.validate().is_ok());
}

#[test]
fn names_parse_with_one_message() {
    assert_eq!(
        "camis".parse::<Mode>(),
        Ok(Mode::Bdpm(HeuristicKind::Camis))
    );
    assert_eq!("light".parse::<Mode>(), Ok(Mode::Light));
    let e = "fast".parse::<Mode>().unwrap_err();
    assert_eq!(e.setting(), Setting::Mode);
    assert_eq!(
        e.to_string(),
        format!(
            "unknown mode 'fast'; expected one of {}",
            Mode::names().join(", ")
        )
    );
    assert!(e.to_string().contains("path, light, bdd0"), "{e}");
    let e = "sobol".parse::<Sampler>().unwrap_err();
    assert_eq!(
        e.to_string(),
        "unknown sampler 'sobol'; expected one of independent, stratified"
    );
}

#[test]
fn partial_settings_apply_check_and_name_their_setting() {
    let mut s = RenderSettings::default();
    let p = PartialSettings {
        resolution: Some(vec![32, 16]),
        mode: Some("threshold".into()),
        threshold_radius: Some(0.5),
        radius: Some(RadiusInput::Text("1.5px".into())),
        noise_model: Some("pinhole".into()),
        pixel_jitter: Some(false),
        cache_photons: Some(7),
        ..PartialSettings::default()
    };
    p.apply(&mut s).unwrap();
    assert_eq!((s.width, s.height, s.radius_px), (32, 16, Some(1.5)));
    assert_eq!(s.heuristic(), Some(Heuristic::Threshold { radius: 0.5 }));
    assert_eq!(
        (s.noise_model, s.pixel_jitter, s.cache_photons),
        (NoiseModel::Pinhole, false, Some(7))
    );
    // Fields not given keep their values.
    assert_eq!(s.spp, RenderSettings::default().spp);
    PartialSettings::default().apply(&mut s).unwrap();
    assert_eq!(s.radius_px, Some(1.5));
    let error = |p: PartialSettings| {
        let e = p.apply(&mut RenderSettings::default()).unwrap_err();
        (e.setting(), e.to_string())
    };
    let (setting, m) = error(PartialSettings {
        resolution: Some(vec![1, 2, 3]),
        ..PartialSettings::default()
    });
    assert_eq!(setting, Setting::Resolution);
    assert!(m.contains("3 values given"), "{m}");
    let (setting, m) = error(PartialSettings {
        noise_model: Some("wide".into()),
        ..PartialSettings::default()
    });
    assert_eq!(setting, Setting::NoiseModel);
    assert!(m.contains("unknown noise model 'wide'"), "{m}");
    let (setting, m) = error(PartialSettings {
        radius: Some(RadiusInput::Metres(1e300)),
        ..PartialSettings::default()
    });
    assert_eq!(setting, Setting::Radius);
    assert!(m.starts_with("1e300 is beyond"), "{m}");
    let (setting, m) = error(PartialSettings {
        radius: Some(RadiusInput::Text("1 pixel".into())),
        ..PartialSettings::default()
    });
    assert_eq!(setting, Setting::Radius);
    assert!(m.contains("not a radius"), "{m}");
    let (setting, m) = error(PartialSettings {
        threshold_radius: Some(1e-39),
        ..PartialSettings::default()
    });
    assert_eq!(setting, Setting::ThresholdRadius);
    assert!(m.contains("1e-39") && m.contains("normal"), "{m}");
    let (setting, _) = error(PartialSettings {
        spp: Some(0),
        ..PartialSettings::default()
    });
    assert_eq!(setting, Setting::Spp);
}

#[test]
fn lengths_are_checked_as_written() {
    assert_eq!(metres(0.25), Ok(0.25));
    assert_eq!(metres(-1.0), Err(LengthError::NotPositive(-1.0)));
    assert_eq!(metres(1e300), Err(LengthError::BeyondSingle(1e300)));
    assert_eq!(metres(1e-39), Err(LengthError::BelowNormal(1e-39)));
    assert_eq!(number_text(1e300), "1e300");
    assert_eq!(number_text(0.25), "0.25");
}

#[cfg(feature = "serde")]
#[test]
fn serde_round_trip() {
    let s = RenderSettings {
        mode: Mode::parse("threshold").unwrap(),
        threshold_radius: 0.4,
        radius_px: Some(1.5),
        sampler: Sampler::Independent,
        ..RenderSettings::default()
    };
    let text = serde_json::to_string(&s).unwrap();
    assert!(
        text.contains(r#""mode":"threshold","threshold_radius":0.4,"#),
        "{text}"
    );
    assert!(text.contains(r#""noise_model":"footprint","sampler":"independent""#));
    let back: RenderSettings = serde_json::from_str(&text).unwrap();
    assert_eq!(back, s);
    // Unknown keys and names are refused, the names listed.
    let typo = text.replace("\"spp\"", "\"sp\"");
    let e = serde_json::from_str::<RenderSettings>(&typo).unwrap_err();
    assert!(e.to_string().contains("unknown field `sp`"), "{e}");
    let bad = text.replace("\"threshold\"", "\"fast\"");
    let e = serde_json::from_str::<RenderSettings>(&bad).unwrap_err();
    assert!(
        e.to_string()
            .contains("unknown mode 'fast'; expected one of path, light"),
        "{e}"
    );
    assert!(
        serde_json::to_string(&s.record(0.1, false, None))
            .unwrap()
            .contains("\"threshold_radius_m\"")
    );
}

/// The documented bounds of every bounded `[render]` setting, as a user writes them: the
/// minimum and the maximum accepted, the nearest numbers outside refused. Before, numbers were
/// compared after their conversion to f32, so that `1000.00001px` and `9.99999999e-19` (metres)
/// rounded onto their bounds and were accepted.
#[test]
fn every_bound_is_exact_as_written() {
    let try_set = |key: &str, text: &str| {
        let mut p = PartialSettings::default();
        p.set(key, &Written::from_text(text))
            .map_err(|e| e.to_string())?;
        p.apply(&mut RenderSettings::default())
            .map_err(|e| e.to_string())
    };
    let ok = |key: &str, text: &str| {
        try_set(key, text).unwrap_or_else(|e| panic!("{key} = {text} refused: {e}"));
    };
    let refused = |key: &str, text: &str, needle: &str| {
        let e = try_set(key, text).expect_err(&format!("{key} = {text} accepted"));
        assert!(e.contains(needle), "{key} = {text}: {e}");
    };
    for (key, setting) in [
        ("passes", Setting::Passes),
        ("photons", Setting::Photons),
        ("spp", Setting::Spp),
        ("cache_bins", Setting::CacheBins),
        ("cache_photons", Setting::CachePhotons),
        ("pixel_table_rays", Setting::PixelTableRays),
        ("direct_boost", Setting::DirectBoost),
    ] {
        let (min, max) = setting.range().expect("a count");
        let bounds = format!("[{min}, {max}]");
        ok(key, &min.to_string());
        ok(key, &max.to_string());
        refused(key, &(min - 1).to_string(), &bounds);
        refused(key, &(max + 1).to_string(), &bounds);
    }
    let side = limits::MAX_RESOLUTION;
    let resolution = |w: i128, h: i128| {
        let mut p = PartialSettings::default();
        let list = Written::List(vec![Written::Whole(w), Written::Whole(h)]);
        p.set("resolution", &list).map_err(|e| e.to_string())?;
        p.apply(&mut RenderSettings::default())
            .map_err(|e| e.to_string())
    };
    assert_eq!(resolution(1, side.into()), Ok(()));
    for (w, h) in [(0, 1), (1, i128::from(side) + 1)] {
        let e = resolution(w, h).unwrap_err();
        assert!(e.contains(&format!("outside [1, {side}]")), "{e}");
    }
    let mut p = PartialSettings::default();
    let e = p
        .set(
            "resolution",
            &Written::List(vec![Written::Whole(8), Written::Whole(0)]),
        )
        .unwrap_err();
    assert_eq!(e.field, "resolution[1]");
    ok("radius", "1000px");
    refused("radius", "1000.00001px", "in (0, 1000]");
    ok("radius", "1e-18");
    ok("radius", "1e-18m");
    refused(
        "radius",
        "9.99999999e-19",
        "below the smallest usable merge radius",
    );
    ok("threshold_radius", "1.1754943508222875e-38");
    refused("threshold_radius", "1e-39", "normal");
    ok("seed", &u64::MAX.to_string());
    refused("seed", "-1", "outside [0, 18446744073709551615]");
    ok("roulette_depth", "0");
    refused("roulette_depth", "-1", "outside [0, 4294967295]");
}

/// A combination is checked once, on the final settings: `apply` lets a scene file's light
/// tracing without jitter through, so that an override can put it right, and `validate`
/// refuses it if none does.
#[test]
fn combinations_are_checked_on_the_final_settings() {
    let file = PartialSettings {
        light_tracing: Some(true),
        pixel_jitter: Some(false),
        ..PartialSettings::default()
    };
    let mut s = RenderSettings::default();
    file.apply(&mut s).unwrap();
    assert_eq!(s.validate(), Err(SettingsError::LightTracingWithoutJitter));
    let flag = PartialSettings {
        light_tracing: Some(false),
        ..PartialSettings::default()
    };
    flag.apply(&mut s).unwrap();
    assert_eq!(s.validate(), Ok(()));
}

/// A value of the wrong kind is named with its key and what was expected, whatever key it is.
#[cfg(feature = "serde")]
#[test]
fn render_values_of_the_wrong_kind_say_what_was_expected() {
    let error = |json: &str| {
        serde_json::from_str::<PartialSettings>(json)
            .unwrap_err()
            .to_string()
    };
    for (json, message) in [
        (
            r#"{"radius": true}"#,
            r#"render.radius: expected a length in metres (0.01) or pixel footprints ("0.2px"), found a boolean"#,
        ),
        (
            r#"{"radius": "-1px"}"#,
            "render.radius: -1 px: the radius must be positive",
        ),
        (
            r#"{"passes": "x"}"#,
            r#"render.passes: expected a whole number in [1, 4294967295], found the text "x""#,
        ),
        (
            r#"{"passes": -1}"#,
            "render.passes: -1 is outside [1, 4294967295]",
        ),
        (
            r#"{"photons": 1e9}"#,
            "render.photons: expected a whole number in [1, 1000000000], found the number 1e9",
        ),
        (
            r#"{"pixel_jitter": 1}"#,
            "render.pixel_jitter: expected true or false, found the integer 1",
        ),
        (
            r#"{"mode": 3}"#,
            "render.mode: expected a mode name (path, light, bdd0",
        ),
        (r#"{"mode": "fast"}"#, "render.mode: unknown mode 'fast'"),
        (
            r#"{"resolution": [8]}"#,
            "render.resolution: 1 values given; expected [width, height] in pixels",
        ),
        (
            r#"{"threshold_radius": "a"}"#,
            r#"render.threshold_radius: expected a length in metres (0.2), found the text "a""#,
        ),
        (
            r#"{"output": {"a": 1}}"#,
            "render.output: expected a file path, found a table",
        ),
        (
            r#"{"sp": 1}"#,
            "unknown field `sp`, expected one of `resolution`",
        ),
    ] {
        let e = error(json);
        assert!(e.starts_with(message), "{json}: {e}");
    }
    let p: PartialSettings =
        serde_json::from_str(r#"{"radius": 1, "resolution": [4, 2], "mode": "path"}"#).unwrap();
    assert_eq!(p.radius, Some(RadiusInput::Metres(1.0)));
    assert_eq!(p.resolution, Some(vec![4, 2]));
}
