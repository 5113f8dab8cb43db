//! `eddy lookup` and `eddy info`: query and summarise a database from the command line.

use std::io::Write;
use std::path::PathBuf;

use eddy::abl::{AblDatabase, MotionKind};
use eddy::{Real, Vec3};

/// Options of `eddy lookup`.
#[derive(Debug, Clone, clap::Args)]
pub struct LookupArgs {
    /// The database (HDF5).
    pub database: PathBuf,
    /// Object velocity relative to the fluid, object frame, m/s: x,y,z.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true, default_value = "0,0,0")]
    pub velocity: Vec3,
    /// Object angular velocity, object frame, rad/s: x,y,z.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true, default_value = "0,0,0")]
    pub angular: Vec3,
    /// Write x, y, z, nx, ny, nz, omega_x, omega_y, omega_z per boundary point here (`-`:
    /// standard output).
    #[arg(long)]
    pub csv: PathBuf,
}

/// Options of `eddy info`.
#[derive(Debug, Clone, clap::Args)]
pub struct InfoArgs {
    /// The database (HDF5).
    pub database: PathBuf,
}

/// Reads `x,y,z`.
fn parse_vec3(s: &str) -> Result<Vec3, String> {
    let parts: Vec<Real> = s
        .split(',')
        .map(|p| p.trim().parse::<Real>().map_err(|e| format!("`{p}`: {e}")))
        .collect::<Result<_, _>>()?;
    match parts[..] {
        [x, y, z] if parts.iter().all(|v| v.is_finite()) => Ok(Vec3::new(x, y, z)),
        _ => Err(format!("expected three finite numbers x,y,z, got `{s}`")),
    }
}

/// Runs `eddy lookup`.
pub fn lookup(args: &LookupArgs) -> anyhow::Result<()> {
    let db = AblDatabase::open(&args.database, None)?;
    let omega = db.lookup(&args.velocity, &args.angular);
    if omega.iter().any(|w| !w.iter().all(|c| c.is_finite())) {
        anyhow::bail!(
            "the looked-up values overflow (are not finite) for --velocity {:?} and --angular \
             {:?}: use physical speeds",
            args.velocity.as_slice(),
            args.angular.as_slice()
        );
    }
    let write = |out: &mut dyn std::io::Write| -> std::io::Result<()> {
        writeln!(out, "x,y,z,nx,ny,nz,omega_x,omega_y,omega_z")?;
        for ((p, n), w) in db.points().iter().zip(db.normals()).zip(&omega) {
            writeln!(
                out,
                "{},{},{},{},{},{},{},{},{}",
                p.x, p.y, p.z, n.x, n.y, n.z, w.x, w.y, w.z
            )?;
        }
        Ok(())
    };
    if args.csv.as_os_str() == "-" {
        let mut stdout = std::io::stdout().lock();
        write(&mut stdout).and_then(|()| stdout.flush())?;
    } else {
        eddy::io::write_atomic(&args.csv, write)?;
    }
    eprintln!(
        "eddy: {} boundary points -> {}",
        omega.len(),
        args.csv.display()
    );
    Ok(())
}

/// Runs `eddy info`: what the database holds and how it was made.
pub fn info(args: &InfoArgs) -> anyhow::Result<()> {
    let db = AblDatabase::open(&args.database, None)?;
    let h = db.header();
    println!("database          {}", db.path().display());
    println!("obstacle          {}", h.obstacle);
    println!("fingerprint       {}", h.fingerprint);
    println!("geometry          {}", h.geometry_fingerprint);
    println!("boundary points   {}", db.len());
    println!("beta              {}", h.beta);
    println!("layer thickness   {} m", h.layer_thickness);
    println!("grid spacing      {} m", h.spacing);
    for kind in MotionKind::ALL {
        let t = db.data().table(kind);
        let max = t
            .omega
            .chunks_exact(3)
            .map(|c| Vec3::new(c[0], c[1], c[2]).norm())
            .fold(0.0, Real::max);
        println!(
            "{:<17} {} polar x {} azimuth samples, max |omega| {max:.4} per unit speed",
            kind.name(),
            t.sampling.polar,
            t.sampling.azimuth
        );
    }
    println!("settings:\n{}", h.settings.trim_end());
    Ok(())
}
