//! The render settings' flags, built from their one description
//! (`furnace_render::fields::FIELDS`): a flag per field, with its help, default, values and
//! checks, parsed into a [`RenderSettings`]. `render` and `view` take every field, `bench` the
//! fields it measures ([`Scope`]).

use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
use clap::error::ErrorKind;
use clap::parser::ValueSource;
use clap::{Arg, ArgAction, ArgMatches, Args, Command, FromArgMatches};
use furnace_render::fields::{FIELDS, Field};
use furnace_render::{Choice, RenderSettings};
use std::collections::BTreeSet;
use std::marker::PhantomData;

/// Which fields a subcommand takes as flags.
pub trait Scope: Clone + std::fmt::Debug + Send + Sync + 'static {
    /// Whether the subcommand takes `field`.
    fn takes(field: &Field) -> bool;
}

/// `furnace render` and `view`: every field.
#[derive(Debug, Clone)]
pub struct Render;

impl Scope for Render {
    fn takes(_: &Field) -> bool {
        true
    }
}

/// `furnace bench`: the fields whose speed it measures.
#[derive(Debug, Clone)]
pub struct Bench;

impl Scope for Bench {
    fn takes(field: &Field) -> bool {
        field.bench
    }
}

/// The settings given by the flags of `S` (the others at their defaults).
#[derive(Debug, Clone)]
pub struct SettingsArgs<S> {
    /// The settings: the flags' values, else [`RenderSettings::default`]'s (the image size and
    /// the fixed-N sample count are the subcommand's to set).
    pub settings: RenderSettings,
    /// The flags given on the command line (not defaulted).
    pub given: BTreeSet<&'static str>,
    scope: PhantomData<S>,
}

impl<S> SettingsArgs<S> {
    /// Whether flag `flag` (without the dashes) was given on the command line.
    pub fn given(&self, flag: &str) -> bool {
        self.given.contains(flag)
    }
}

/// A parser of the values of choice `T` by name, listing them with their help.
pub fn choice<T: Choice>() -> impl TypedValueParser<Value = T> {
    PossibleValuesParser::new(T::VALUES.iter().map(|v| PossibleValue::new(v.name()).help(v.help())))
        .try_map(|s| T::from_name(&s).ok_or_else(|| format!("'{s}' is not a value")))
}

/// The flag of `field`.
fn arg(field: &'static Field) -> Arg {
    let mut arg = Arg::new(field.flag)
        .long(field.flag)
        .help(field.help)
        .value_name(field.value_name)
        .action(ArgAction::Set);
    if let Some(default) = field.default {
        arg = arg.default_value(default);
    }
    if let Some(other) = field.requires {
        arg = arg.requires(other);
    }
    let choices = (field.choices)();
    if choices.is_empty() {
        // A number: checked as the field checks it, so that a negative one reaches the check.
        let set = field.set;
        arg.allow_negative_numbers(true).value_parser(move |s: &str| -> Result<String, String> {
            set(&mut RenderSettings::default(), s).map(|()| s.to_string())
        })
    } else {
        arg.value_parser(PossibleValuesParser::new(
            choices.into_iter().map(|(name, help)| PossibleValue::new(name).help(help)),
        ))
    }
}

impl<S: Scope> Args for SettingsArgs<S> {
    fn augment_args(cmd: Command) -> Command {
        FIELDS.iter().filter(|f| S::takes(f)).fold(cmd, |cmd, f| cmd.arg(arg(f)))
    }

    fn augment_args_for_update(cmd: Command) -> Command {
        Self::augment_args(cmd)
    }
}

impl<S: Scope> FromArgMatches for SettingsArgs<S> {
    fn from_arg_matches(matches: &ArgMatches) -> Result<Self, clap::Error> {
        let mut args =
            Self { settings: RenderSettings::default(), given: BTreeSet::new(), scope: PhantomData };
        args.update_from_arg_matches(matches)?;
        Ok(args)
    }

    fn update_from_arg_matches(&mut self, matches: &ArgMatches) -> Result<(), clap::Error> {
        // In table order: the noise threshold turns adaptive sampling on before its minimum is set.
        for f in FIELDS.iter().filter(|f| S::takes(f)) {
            if let Some(value) = matches.get_one::<String>(f.flag) {
                (f.set)(&mut self.settings, value)
                    .map_err(|e| clap::Error::raw(ErrorKind::InvalidValue, e))?;
            }
            if matches.value_source(f.flag) == Some(ValueSource::CommandLine) {
                self.given.insert(f.flag);
            }
        }
        Ok(())
    }
}
