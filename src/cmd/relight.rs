//! `flatland relight`: one scene lit again and again — a light at many positions (`--light`,
//! `--path` or `--walk`), each relit by the exact re-solve ([`Relighter`]: the operator built
//! once, per move the direct light, the first bounce from the lit columns and the later bounces
//! warm-started) or by the learned transport of the later bounces (`--kernel transport|MODEL`:
//! the same direct light and first bounce, the later bounces from a model built once), timed
//! per move, optionally checked against a cold exact solve at each position, written as CSV or
//! one PNG per position.

mod transport;

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use anyhow::{Context, Result, bail};
use flatland_geom::{
    AtomicFile, DVec2, GeomError, Kernel, LightCheck, PointLight, in_a_room, write_atomic,
};
use flatland_lab::timed::walk::{
    ExactMover, MoveRecord, Mover, WalkFigures, lamp_moves, relight_elements, relight_moves,
};
use flatland_lab::{interrupt, output};
use flatland_pictures::lit::{Panel, panel_png};
use flatland_pictures::plan::{PlanColours, lit_plan_by};
use flatland_solve::{
    RADIOSITY_HEADER, RelightParams, Relighter, SolveError, Stop, check_elements, line_along,
    radiosity_rows,
};

use super::SceneArgs;

/// Arguments of `flatland relight`.
#[derive(clap::Args, Debug)]
#[command(group(
    clap::ArgGroup::new("positions").required(true).args(["light", "path", "walk"])
))]
pub struct Args {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// One position of the light, `X,Y` or `X,Y,POWER` (power default: the scene's first
    /// light's, else 1); repeat it for more positions. The light replaces the scene's point
    /// lights; its emitting edges stay on as static light.
    #[arg(long, value_name = "X,Y[,POWER]", allow_hyphen_values = true)]
    pub light: Vec<String>,
    /// A file of positions, one `X,Y` or `X,Y,POWER` a line (blank lines and lines starting
    /// with `#` are skipped).
    #[arg(long, value_name = "FILE")]
    pub path: Option<PathBuf>,
    /// N positions of a walk through the scene's rooms and doors, from --seed: each step a
    /// fraction of the free space around it, never through an edge nor near one.
    #[arg(long, value_name = "N")]
    pub walk: Option<usize>,
    /// The walk's seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// The re-solve: exact, or transport (the learned transport of the later bounces, built
    /// here: worth its set-up after about a thousand moves) or a model file of it saved by
    /// --save-model (refused for another scene or mesh).
    #[arg(long, value_name = "KERNEL", default_value = "exact")]
    pub kernel: String,
    /// Save the learned transport built by --kernel transport to M, to query later with
    /// --kernel M.
    #[arg(long, value_name = "M")]
    pub save_model: Option<PathBuf>,
    /// Elements of the mesh (default: four per section of a surface edge, at least 512: what
    /// `flatland solve` chooses for a 1 % error on generated plans and halls).
    #[arg(long, value_name = "N")]
    pub elements: Option<usize>,
    /// Each move's solve stops at this relative residual, in (0, 0.1]; B is then within about
    /// this of the exact solve.
    #[arg(long, value_name = "X", default_value_t = RelightParams::default().tolerance)]
    pub tolerance: f64,
    /// Write B at every position: a `.csv` file (`position,edge,s,x,y,b`, one block of rows per
    /// position) or a folder (per position a PNG of the lit scene and the lit plan as SVG —
    /// each element a segment in its B colour carrying `data-b` —, the lights marked, one
    /// colour scale for every position).
    #[arg(long, value_name = "B.csv|DIR")]
    pub out: Option<PathBuf>,
    /// Print one JSON object: setup_s, bytes, positions, ms_per_move_median,
    /// ms_per_move_p95 (and with --check rel_l2_b_mean, rel_l2_b_max, rel_l2_indirect_mean).
    #[arg(long)]
    pub json: bool,
    /// Check each position against a full, cold, independent exact solve there (its own lit
    /// mesh, solved from B = B₀ to 1e-10): the relative L2 error of B and of the indirect part
    /// B − B₀ (B minus the direct light and the emission).
    #[arg(long)]
    pub check: bool,
}

/// Where B goes.
enum Output {
    Csv(PathBuf),
    Pictures(PathBuf),
}

/// Runs `flatland relight`.
pub fn run(args: &Args) -> Result<()> {
    let choice = transport::choice(&args.kernel)?;
    if let Some(model) = &args.save_model {
        if !matches!(choice, transport::Choice::Transport) {
            bail!(
                "--save-model {}: saves the learned transport this run builds; it goes with \
                 --kernel transport",
                model.display()
            );
        }
        output::file(model, &args.scene.path().into_iter().collect::<Vec<_>>())?;
    }
    let output = output_of(args)?;
    let (scene, label) = args.scene.load()?;
    let kernel = Kernel::new(scene);
    let elements = args
        .elements
        .unwrap_or_else(|| relight_elements(kernel.scene()));
    check_elements(&kernel, elements).context("--elements")?;
    let params = RelightParams {
        tolerance: args.tolerance,
        ..RelightParams::default()
    };
    params.check().context("--tolerance")?;
    let moves = positions(args, &kernel)?;
    let exact = set_up(&kernel, elements, params)?;
    let save = args.save_model.as_deref();
    let mut mover: Box<dyn Mover> = match &choice {
        transport::Choice::Exact => Box::new(ExactMover::of(exact.with_params(params)?)),
        transport::Choice::Transport => {
            Box::new(transport::mover(&kernel, &exact, params, None, save)?)
        }
        transport::Choice::Model(path) => {
            Box::new(transport::mover(&kernel, &exact, params, Some(path), None)?)
        }
    };
    let done = relight(
        args,
        &kernel,
        &label,
        (mover.as_mut(), &exact),
        &moves,
        output.as_ref(),
    )?;
    let figures = WalkFigures::of(&done.records);
    report(
        args,
        &label,
        (mover.as_ref(), &exact),
        moves.len(),
        &figures,
    );
    if done.stopped {
        let kept = kept_note(output.as_ref(), done.records.len(), moves.len());
        interrupt::keep(kept);
        return Err(interrupt::stopped().into());
    }
    Ok(())
}

/// The output `--out` names, checked before any work.
fn output_of(args: &Args) -> Result<Option<Output>> {
    let Some(out) = &args.out else {
        return Ok(None);
    };
    let inputs: Vec<&Path> = args
        .scene
        .path()
        .into_iter()
        .chain(args.path.as_deref())
        .collect();
    let csv = out
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("csv"));
    if csv {
        output::file(out, &inputs)?;
        Ok(Some(Output::Csv(out.clone())))
    } else {
        output::folder(out, &[], &inputs)?;
        Ok(Some(Output::Pictures(out.clone())))
    }
}

/// The moves asked for: one light each, checked against the scene's edges (named by flag,
/// position or file line); a warning for a light outside every room.
fn positions(args: &Args, kernel: &Kernel) -> Result<Vec<Vec<PointLight>>> {
    let power = kernel.scene().lights().first().map_or(1.0, |l| l.power);
    let check = LightCheck::new(kernel.scene());
    let given: Vec<(String, PointLight)> = if let Some(n) = args.walk {
        let moves = lamp_moves(kernel, n, args.seed, power).context("--walk")?;
        return Ok(moves);
    } else if let Some(path) = &args.path {
        let text =
            std::fs::read_to_string(path).with_context(|| format!("--path {}", path.display()))?;
        let lines = text.lines().enumerate();
        let wanted = lines.filter(|(_, l)| !l.trim().is_empty() && !l.trim().starts_with('#'));
        wanted
            .map(|(k, line)| {
                let at = format!("{}:{}", path.display(), k + 1);
                parse_light(line, power)
                    .map(|l| (at.clone(), l))
                    .with_context(|| at)
            })
            .collect::<Result<_>>()?
    } else {
        let each = args.light.iter().enumerate();
        each.map(|(k, text)| {
            let at = format!("--light {} ({text})", k + 1);
            parse_light(text, power)
                .map(|l| (at.clone(), l))
                .with_context(|| at)
        })
        .collect::<Result<_>>()?
    };
    if given.is_empty() {
        bail!("--path: no position in the file (one X,Y or X,Y,POWER a line)");
    }
    for (at, light) in &given {
        check.check(&[*light]).map_err(|e| light_error(at, e))?;
    }
    let outside: Vec<&str> = given
        .iter()
        .filter(|(_, l)| !in_a_room(kernel, l.at))
        .map(|(at, _)| at.as_str())
        .collect();
    if let Some(first) = outside.first() {
        eprintln!(
            "warning: {} of {} positions are outside every room (a ray from them meets the back \
             of a wall): they light only what faces them from outside; the first is {first}",
            outside.len(),
            given.len()
        );
    }
    Ok(given.into_iter().map(|(_, l)| vec![l]).collect())
}

/// A light refused by the scene, named by where it was given.
fn light_error(at: &str, e: GeomError) -> anyhow::Error {
    match e {
        GeomError::LightOnEdge { edge, .. } => anyhow::anyhow!(
            "{at}: lies on edge {edge}; a light must be off every edge (move it into the room, \
             even a little)"
        ),
        GeomError::LightPower { value, .. } => {
            anyhow::anyhow!("{at}: power must be finite and >= 0, but is {value}")
        }
        GeomError::LightNonFinite { field, value, .. } => {
            anyhow::anyhow!("{at}: {field} must be finite, but is {value}")
        }
        other => anyhow::anyhow!("{at}: {other}"),
    }
}

/// `X,Y` or `X,Y,POWER`.
fn parse_light(text: &str, power: f64) -> Result<PointLight> {
    let numbers: Vec<f64> = text
        .split(',')
        .map(|v| v.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| anyhow::anyhow!("`{}` is not X,Y or X,Y,POWER (numbers)", text.trim()))?;
    match numbers[..] {
        [x, y] => Ok(PointLight::new(DVec2::new(x, y), power)),
        [x, y, p] => Ok(PointLight::new(DVec2::new(x, y), p)),
        _ => bail!(
            "`{}` is not X,Y or X,Y,POWER: {} numbers",
            text.trim(),
            numbers.len()
        ),
    }
}

/// The relighter, a bar over the operator's rows as it is built.
fn set_up(kernel: &Kernel, elements: usize, params: RelightParams) -> Result<Relighter> {
    let mesh = flatland_solve::Mesh::new(kernel, elements)?;
    let rows = mesh.len() as u64;
    let bar = super::progress_bar(rows, "rows of the operator");
    let polled = AtomicU64::new(0);
    let ticking = bar.clone();
    // The set-up polls its stop once per row of the operator: the bar counts the polls.
    let stop = move || {
        let polls = polled.fetch_add(1, Ordering::Relaxed) + 1;
        if polls.is_multiple_of(256) {
            ticking.set_position(polls.min(rows));
        }
        interrupt::requested()
    };
    let relighter = Relighter::new(kernel, &mesh, params, &stop).map_err(|e| match e {
        SolveError::Interrupted => interrupt::stopped().into(),
        other => anyhow::Error::from(other).context("building the exact operator"),
    });
    bar.finish_and_clear();
    relighter
}

/// What the moves gave.
struct Done {
    records: Vec<MoveRecord>,
    stopped: bool,
}

/// Every move, written as `--out` asks.
fn relight(
    args: &Args,
    kernel: &Kernel,
    label: &str,
    (mover, exact): (&mut dyn Mover, &Relighter),
    moves: &[Vec<PointLight>],
    output: Option<&Output>,
) -> Result<Done> {
    let mesh = exact.mesh().clone();
    let mut csv = match output {
        Some(Output::Csv(path)) => {
            let mut file = AtomicFile::create(path)?;
            writeln!(file, "position,{RADIOSITY_HEADER}")?;
            Some(file)
        }
        _ => None,
    };
    eprintln!(
        "relight: set up in {:.2} s; relighting {} positions (Ctrl-C keeps those done)",
        mover.setup_s(),
        moves.len()
    );
    let bar = super::progress_bar(moves.len() as u64, "positions");
    let digits = moves.len().to_string().len();
    let mut scale = None;
    let stop: &Stop = &interrupt::requested;
    let (records, stopped) =
        relight_moves(mover, exact, kernel, moves, args.check, stop, |k, b| {
            bar.set_position(k as u64 + 1);
            if let Some(file) = csv.as_mut() {
                radiosity_rows(file, &format!("{k},"), &mesh, b)?;
            }
            if let Some(Output::Pictures(dir)) = output {
                let colours = *scale.get_or_insert_with(|| PlanColours::new(&mesh, b));
                let top = colours.scale().top;
                // No gather per move (it would cost a view per point of every picture): B
                // along each element is the line through the midpoints.
                let along = line_along(&mesh, b);
                let panel = Panel {
                    scene: kernel.scene(),
                    caption: format!("{label}: position {k} of {}", moves.len()),
                    mesh: &mesh,
                    b,
                    along: &along,
                    lights: &moves[k],
                    top,
                };
                let png = panel_png(&panel)?;
                let path = dir.join(format!("position-{k:0digits$}.png"));
                interrupt::writing(|| write_atomic(&path, &png))?;
                let title = &panel.caption;
                let scene = kernel.scene();
                let plan = lit_plan_by(scene, &mesh, b, &along, &moves[k], title, &colours);
                let path = path.with_extension("svg");
                interrupt::writing(|| write_atomic(&path, plan.svg().as_bytes()))?;
            }
            Ok(())
        })?;
    bar.finish_and_clear();
    if let Some(file) = csv {
        interrupt::writing(|| file.commit())?;
    }
    Ok(Done { records, stopped })
}

/// The figures: one JSON object, or lines for a reader.
fn report(args: &Args, label: &str, run: (&dyn Mover, &Relighter), asked: usize, f: &WalkFigures) {
    let (mover, r) = run;
    if args.json {
        let mut json = serde_json::json!({
            "setup_s": mover.setup_s(),
            "bytes": mover.bytes(),
            "positions": f.positions,
            "ms_per_move_median": f.ms_median,
            "ms_per_move_p95": f.ms_p95,
        });
        if args.check {
            json["rel_l2_b_mean"] = f.rel_l2_b_mean.into();
            json["rel_l2_b_max"] = f.rel_l2_b_max.into();
            json["rel_l2_indirect_mean"] = f.rel_l2_indirect_mean.into();
        }
        println!("{json}");
        return;
    }
    let exact = mover.method() == flatland_methods::Method::Exact;
    let method = if exact {
        format!(
            "the exact re-solve to a relative residual of {:e}",
            r.params().tolerance
        )
    } else {
        format!(
            "the learned transport of the later bounces ({})",
            mover.setting()
        )
    };
    println!(
        "relight of {label}: {} elements, {} of {asked} positions, {method}",
        r.mesh().len(),
        f.positions,
    );
    println!(
        "set-up {:.2} s, {:.1} MB (the operator by rows and by columns, {} numbers each{})",
        mover.setup_s(),
        mover.bytes() as f64 / 1e6,
        r.rows().nonzeros(),
        if exact { "" } else { ", and the transport" }
    );
    let work = if exact {
        format!("; products with K per move {:.1}", f.work_mean)
    } else {
        String::new()
    };
    println!(
        "ms per move: median {:.2}, p95 {:.2}{work}",
        f.ms_median, f.ms_p95
    );
    if let (Some(mean), Some(max), Some(indirect)) =
        (f.rel_l2_b_mean, f.rel_l2_b_max, f.rel_l2_indirect_mean)
    {
        println!(
            "against a cold exact solve at each position: rel. L2 of B mean {mean:.2e}, max \
             {max:.2e}; of the indirect part B − B₀ mean {indirect:.2e}"
        );
    }
    if let Some(out) = &args.out {
        println!("wrote {}", out.display());
    }
}

/// What Ctrl-C kept, in words.
fn kept_note(output: Option<&Output>, done: usize, asked: usize) -> String {
    let place = match output {
        Some(Output::Csv(path)) => format!(" in {}", path.display()),
        Some(Output::Pictures(dir)) => format!(" as PNGs in {}", dir.display()),
        None => String::new(),
    };
    format!("{done} of {asked} positions relit, kept{place} and in the figures above")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lights_parse_and_bad_ones_say_what_is_valid() {
        let l = parse_light(" -1.5, 2 ", 8.0).unwrap();
        assert_eq!((l.at, l.power), (DVec2::new(-1.5, 2.0), 8.0));
        assert_eq!(parse_light("1,2,3", 8.0).unwrap().power, 3.0);
        for bad in ["1", "1,2,3,4", "a,b", ""] {
            let err = parse_light(bad, 1.0).unwrap_err().to_string();
            assert!(err.contains("X,Y or X,Y,POWER"), "{bad}: {err}");
        }
    }

    #[test]
    fn kernels_are_exact_transport_or_a_model_and_the_others_say_why() {
        use transport::{Choice, choice};
        assert!(matches!(choice("exact").unwrap(), Choice::Exact));
        assert!(matches!(choice("transport").unwrap(), Choice::Transport));
        let model = choice("runs/t.json").unwrap();
        assert!(matches!(model, Choice::Model(p) if p == Path::new("runs/t.json")));
        let err = choice("hr").err().unwrap().to_string();
        assert!(err.contains("exact or transport"), "{err}");
        let err = choice("exactly").err().unwrap().to_string();
        assert!(err.contains("`exactly` is not a method"), "{err}");
    }
}
