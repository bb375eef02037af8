//! `cachert compare`. Being written.
