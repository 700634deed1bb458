//! A toy integrator (18 % grey) driven by a [`Session`]: `cargo run -p furnace-render --example session`.

use furnace_render::{Budget, Film, Integrator, Progress, RenderError, RenderSettings, Session, Stop};

struct Grey {
    settings: RenderSettings,
    film: Film,
}

#[rustfmt::skip] // one-line methods keep the example short
impl Integrator for Grey {
    fn name(&self) -> &'static str { "grey" }
    fn describe(&self) -> String { "grey: 18 %".into() }
    fn settings(&self) -> &RenderSettings { &self.settings }
    fn render_pass(&mut self, first: u32, n: u32) -> Result<(), RenderError> {
        for _ in first..first + n {
            for mut row in self.film.rows_mut() {
                (0..self.settings.width as usize).for_each(|x| { row.add_sample(x, glam::Vec3::splat(0.18)); });
            }
        }
        Ok(())
    }
    fn film(&mut self) -> Result<Film, RenderError> { Ok(self.film.clone()) }
    fn set_film(&mut self, film: &Film) -> Result<(), RenderError> {
        RenderError::check_film(film, &self.settings).map(|()| self.film = film.clone())
    }
    fn pass_samples(&self) -> u32 { 4 }
}

fn main() -> Result<(), RenderError> {
    let settings = RenderSettings { width: 8, height: 4, ..Default::default() };
    let mut grey = Grey { film: Film::new(settings.width, settings.height), settings };
    let mut session = Session::new(&mut grey, 0);
    let mut report = |p: &Progress| println!("{}/{} spp (+{})", p.done, p.target, p.pass);
    let stop = session.run(&Budget::spp(10), &|| false, &mut report)?;
    let film = session.film()?;
    println!("{stop:?}: pixel (0, 0) = {}, {} samples", film.pixel(0, 0), film.sample_count(0, 0));
    assert_eq!((stop, film.sample_count(7, 3), film.pixel(0, 0).x as f32), (Stop::Finished, 10, 0.18));
    Ok(())
}
