//! STAGE 5 (application): the one list of cache-based integrators, by the names users type (STYLE habit 10:
//! one explicit table, no self-registration). Rendering, `render --help`, the parameter tables of docs/ (a
//! test checks them), `info`, `experiment --integrator` and the error messages that list integrators all read
//! it. Registering an application is one line in the `applications!` invocation below.
//!
//! Depends only on the applications of this module's parent.

use crate::parse::integrator::Parameter;

use super::ambient_occlusion::CacheAo;
use super::importance::ImportanceCache;
use super::irradiance::IrradianceCache;
use super::{Application, PerSample};

/// What is known about a registered application without its type: name, summary, parameter table.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Entry {
    /// The integrator name (`Application::NAME`).
    pub name: &'static str,
    /// One line saying what it renders (`Application::ABOUT`).
    pub about: &'static str,
    /// Its own parameters (`Application::PARAMETERS`).
    pub parameters: &'static [Parameter],
    /// Settings for small, fast renders (`Study::quick` of `Application::STUDY`).
    pub quick: &'static [(&'static str, &'static str)],
    /// The paper's budget at 1920×1080 (`Application::PAPER_CACHES`).
    pub paper_caches: usize,
    /// [`Application::PATH_DEPTH`].
    pub path_depth: Option<&'static str>,
    /// Its own estimator per pixel (`Study::per_sample` of `Application::STUDY`).
    pub per_sample: Option<PerSample>,
}

impl Entry {
    /// The entry of application `A`.
    pub const fn of<A: Application>() -> Self {
        Entry {
            name: A::NAME,
            about: A::ABOUT,
            parameters: A::PARAMETERS,
            quick: A::STUDY.quick,
            paper_caches: A::PAPER_CACHES,
            path_depth: A::PATH_DEPTH,
            per_sample: A::STUDY.per_sample,
        }
    }
}

/// Something to do with an application chosen by name at run time: [`dispatch`] calls
/// [`WithApplication::apply`] with the application's type (the render driver, `experiment`, tests).
pub trait WithApplication {
    /// What it gives.
    type Output;
    /// Does it with application `A`.
    fn apply<A: Application>(self) -> Self::Output;
}

macro_rules! applications {
    ($($app:ty),+ $(,)?) => {
        /// Every registered cache-based integrator, in the order help and reports list them.
        pub const APPLICATIONS: &[Entry] = &[$(Entry::of::<$app>()),+];

        /// Runs `w` with the application named `name`; `None` when no cache-based integrator has that name.
        pub fn dispatch<W: WithApplication>(name: &str, w: W) -> Option<W::Output> {
            $(
                if name == <$app as Application>::NAME {
                    return Some(w.apply::<$app>());
                }
            )+
            None
        }
    };
}

// The registry: one line per application.
applications! {
    CacheAo,
    IrradianceCache,
    ImportanceCache,
}

/// The registered names, comma-separated (for messages).
pub fn names() -> String {
    APPLICATIONS.iter().map(|e| e.name).collect::<Vec<_>>().join(", ")
}

/// The entry named `name`.
pub fn entry(name: &str) -> Option<&'static Entry> {
    APPLICATIONS.iter().find(|e| e.name == name)
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Name;
    impl WithApplication for Name {
        type Output = &'static str;
        fn apply<A: Application>(self) -> &'static str {
            A::NAME
        }
    }

    #[test]
    fn every_entry_dispatches_to_its_own_type_and_names_are_unique() {
        for e in APPLICATIONS {
            assert_eq!(dispatch(e.name, Name), Some(e.name));
            assert_eq!(APPLICATIONS.iter().filter(|o| o.name == e.name).count(), 1, "{}", e.name);
            assert!(!e.parameters.is_empty() && !e.about.is_empty(), "{}", e.name);
        }
        assert_eq!(dispatch("nope", Name), None);
    }
}
