// latentoc's 3-D view of one result (latentoc/viewer): the scene JSON in #latentoc-scene, three.js as THREE.
// The robot's parts are posed from precomputed world poses (position, quaternion x y z w) per frame;
// the initial motion is a translucent ghost; a contact motion adds each contact point's force and friction
// cone (as many points as the scene names), the support polygon, the COM's ground projection and the ZMP. #t=SECONDS in the address shows that time, paused.
(function () {
  "use strict";
  const S = JSON.parse(document.getElementById("latentoc-scene").textContent);
  const status = document.getElementById("status");
  window.addEventListener("error", function (e) { document.body.dataset.error = String(e.message); });

  function bytes(b64) {
    const bin = atob(b64);
    const out = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; i++) out[i] = bin.charCodeAt(i);
    return out;
  }
  const f32 = (b64) => new Float32Array(bytes(b64).buffer);
  const u16 = (b64) => new Uint16Array(bytes(b64).buffer);
  const u32 = (b64) => new Uint32Array(bytes(b64).buffer);

  // ---------------------------------------------------------------- renderer, camera, lights
  const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  document.getElementById("view").appendChild(renderer.domElement);
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0xf4f5f7);
  const camera = new THREE.PerspectiveCamera(40, 1, 0.01, 100);
  camera.up.set(0, 0, 1); // the models' z points up
  scene.add(new THREE.HemisphereLight(0xffffff, 0x8a8f99, 1.6));
  const sun = new THREE.DirectionalLight(0xffffff, 1.6);
  sun.position.set(2, -3, 5);
  scene.add(sun);

  const lo = new THREE.Vector3().fromArray(S.bounds[0]);
  const hi = new THREE.Vector3().fromArray(S.bounds[1]);
  const centre = lo.clone().add(hi).multiplyScalar(0.5);
  const size = hi.clone().sub(lo);
  const extent = Math.max(size.x, size.y, size.z);

  // the ground: a grid at z = 0 for a free-flying body, under the lowest point for a fixed base
  const groundZ = S.ground ? 0 : lo.z;
  const grid = new THREE.GridHelper(Math.max(4, Math.ceil(2 * extent)), Math.max(8, Math.ceil(20 * extent)), 0xb8bcc4, 0xd8dbe0);
  grid.rotation.x = Math.PI / 2;
  grid.position.set(centre.x, centre.y, groundZ);
  scene.add(grid);

  // ---------------------------------------------------------------- orbit camera (drag, shift/right-drag, wheel)
  // view from the side the motion is widest: along the horizontal axis with the smaller extent
  const orbit = { target: centre.clone(), radius: 1.6 * extent + 0.2, azimuth: size.x < size.y ? 0 : -Math.PI / 2, elevation: 0.25 };
  orbit.azimuth += 0.35;
  function placeCamera() {
    const c = Math.cos(orbit.elevation);
    camera.position.set(orbit.target.x + orbit.radius * c * Math.cos(orbit.azimuth),
      orbit.target.y + orbit.radius * c * Math.sin(orbit.azimuth), orbit.target.z + orbit.radius * Math.sin(orbit.elevation));
    camera.lookAt(orbit.target);
  }
  let drag = null;
  renderer.domElement.addEventListener("contextmenu", (e) => e.preventDefault());
  renderer.domElement.addEventListener("pointerdown", (e) => {
    drag = { x: e.clientX, y: e.clientY, pan: e.button === 2 || e.shiftKey };
    renderer.domElement.setPointerCapture(e.pointerId);
  });
  renderer.domElement.addEventListener("pointerup", () => { drag = null; });
  renderer.domElement.addEventListener("pointermove", (e) => {
    if (!drag) return;
    const dx = e.clientX - drag.x, dy = e.clientY - drag.y;
    drag.x = e.clientX; drag.y = e.clientY;
    if (drag.pan) {
      const k = orbit.radius / renderer.domElement.clientHeight;
      const right = new THREE.Vector3().setFromMatrixColumn(camera.matrixWorld, 0);
      const up = new THREE.Vector3().setFromMatrixColumn(camera.matrixWorld, 1);
      orbit.target.addScaledVector(right, -dx * k).addScaledVector(up, dy * k);
    } else {
      orbit.azimuth -= 0.008 * dx;
      orbit.elevation = Math.min(1.5, Math.max(-1.5, orbit.elevation + 0.008 * dy));
    }
    placeCamera();
  });
  renderer.domElement.addEventListener("wheel", (e) => {
    e.preventDefault();
    orbit.radius *= Math.exp(0.001 * e.deltaY);
    placeCamera();
  }, { passive: false });

  // ---------------------------------------------------------------- the robot's parts
  const meshes = S.meshes.map((m) => {
    const g = new THREE.BufferGeometry();
    g.setAttribute("position", new THREE.BufferAttribute(f32(m.positions), 3));
    g.setIndex(new THREE.BufferAttribute(m.wide ? u32(m.indices) : u16(m.indices), 1));
    g.computeVertexNormals();
    return g;
  });
  function partGeometry(p) {
    let g;
    if (p.kind === "mesh") return meshes[p.mesh];
    if (p.kind === "box") g = new THREE.BoxGeometry(p.size[0], p.size[1], p.size[2]);
    else if (p.kind === "sphere") g = new THREE.SphereGeometry(p.size[0], 24, 16);
    else if (p.kind === "cylinder") g = new THREE.CylinderGeometry(p.size[0], p.size[0], p.size[1], 24);
    else g = new THREE.CapsuleGeometry(p.size[0], p.size[1], 6, 16);
    if (p.kind === "cylinder" || p.kind === "capsule") g.rotateX(Math.PI / 2); // three.js: along y; ours: along z
    return g;
  }
  const geometries = S.parts.map(partGeometry);
  const times = f32(S.times);
  const motions = {};
  function addMotion(name, ghost) { // ghost: the colour of a translucent motion (none: the robot's own colours)
    const group = new THREE.Group();
    const objects = S.parts.map((p, k) => {
      const material = ghost
        ? new THREE.MeshStandardMaterial({ color: ghost, transparent: true, opacity: 0.28, depthWrite: false, roughness: 0.8 })
        : new THREE.MeshStandardMaterial({ color: new THREE.Color().fromArray(p.colour), roughness: 0.55, metalness: 0.05 });
      const o = new THREE.Mesh(geometries[k], material);
      if (ghost) o.renderOrder = 2;
      group.add(o);
      return o;
    });
    scene.add(group);
    motions[name] = { group: group, objects: objects, poses: f32(S.motions[name]) };
  }
  addMotion("optimised", null);
  if (S.motions.initial) addMotion("initial", 0x7fa7d9);
  if (S.motions.simulated) addMotion("simulated", 0xe0823a); // the MuJoCo replay, orange

  // a second model beside the robot (a retargeted motion's source), in its own colours
  let beside = null;
  if (S.beside) {
    const group = new THREE.Group();
    const objects = S.beside.parts.map((p) => {
      const o = new THREE.Mesh(partGeometry(p), new THREE.MeshStandardMaterial({
        color: new THREE.Color().fromArray(p.colour), roughness: 0.55, metalness: 0.05 }));
      group.add(o);
      return o;
    });
    scene.add(group);
    beside = { group: group, objects: objects, poses: f32(S.beside.poses) };
  }

  // ---------------------------------------------------------------- contacts
  let contacts = null;
  if (S.contacts) {
    const C = S.contacts;
    // as many points as the scene names (both feet's), each with its arrow and cone; the polygon's corners
    contacts = { count: C.names.length, corners: C.corners, points: f32(C.points), forces: f32(C.forces),
      active: bytes(C.active), polygon: f32(C.polygon), contact: bytes(C.contact), com: f32(C.com), zmp: f32(C.zmp),
      arrows: [], cones: [], lengths: new Float64Array(C.names.length), arrowGroup: new THREE.Group(), coneGroup: new THREE.Group() };
    const coneGeometry = new THREE.ConeGeometry(C.mu * C.cone_height, C.cone_height, 32, 1, true);
    coneGeometry.rotateX(-Math.PI / 2); // apex down at the contact point, opening up along z
    coneGeometry.translate(0, 0, C.cone_height / 2);
    const coneMaterial = new THREE.MeshStandardMaterial({ color: 0x2e9e5b, transparent: true, opacity: 0.3,
      side: THREE.DoubleSide, depthWrite: false });
    for (let k = 0; k < contacts.count; k++) {
      const arrow = new THREE.ArrowHelper(new THREE.Vector3(0, 0, 1), new THREE.Vector3(), 0.1, 0xd62728, 0.04, 0.025);
      contacts.arrows.push(arrow);
      contacts.arrowGroup.add(arrow);
      const cone = new THREE.Mesh(coneGeometry, coneMaterial);
      cone.renderOrder = 3;
      contacts.cones.push(cone);
      contacts.coneGroup.add(cone);
    }
    const polyGeometry = new THREE.BufferGeometry();
    polyGeometry.setAttribute("position", new THREE.BufferAttribute(new Float32Array(3 * C.corners), 3));
    const fan = [];
    for (let k = 1; k + 1 < C.corners; k++) fan.push(0, k, k + 1); // a convex polygon: a triangle fan
    polyGeometry.setIndex(fan);
    contacts.polygon3 = new THREE.Mesh(polyGeometry, new THREE.MeshBasicMaterial({ color: 0xe3a21a, transparent: true,
      opacity: 0.45, side: THREE.DoubleSide, depthWrite: false }));
    contacts.outline = new THREE.LineLoop(polyGeometry, new THREE.LineBasicMaterial({ color: 0xa06d00 }));
    const dot = (colour) => new THREE.Mesh(new THREE.CylinderGeometry(0.018, 0.018, 0.004, 24).rotateX(Math.PI / 2),
      new THREE.MeshBasicMaterial({ color: colour }));
    contacts.comDot = dot(0x1f4fd1);
    contacts.zmpDot = dot(0xd62728);
    contacts.polygonGroup = new THREE.Group();
    contacts.polygonGroup.add(contacts.polygon3, contacts.outline, contacts.comDot, contacts.zmpDot);
    scene.add(contacts.arrowGroup, contacts.coneGroup, contacts.polygonGroup);
  }

  // ---------------------------------------------------------------- one frame of the motion
  function frameAt(t) { // the last sample at or before t
    let lo = 0, hi = times.length - 1;
    while (lo < hi) { const mid = (lo + hi + 1) >> 1; if (times[mid] <= t + 1e-6) lo = mid; else hi = mid - 1; } // float32 times
    return lo;
  }
  function place(m, i) { // a motion's or the second model's parts at frame i
    const n = m.objects.length, p = m.poses;
    for (let k = 0; k < n; k++) {
      const o = (i * n + k) * 7;
      m.objects[k].position.set(p[o], p[o + 1], p[o + 2]);
      m.objects[k].quaternion.set(p[o + 3], p[o + 4], p[o + 5], p[o + 6]);
    }
  }
  function pose(i) {
    for (const name in motions) place(motions[name], i);
    if (beside) place(beside, i);
    if (contacts) {
      const c = contacts, m = c.count;
      for (let k = 0; k < m; k++) {
        const o = (i * m + k) * 3;
        const at = new THREE.Vector3(c.points[o], c.points[o + 1], c.points[o + 2]);
        const f = new THREE.Vector3(c.forces[o], c.forces[o + 1], c.forces[o + 2]);
        const on = c.active[i * m + k] === 1;
        c.arrows[k].visible = on && f.length() > 1e-4;
        c.lengths[k] = c.arrows[k].visible ? f.length() : 0;
        if (c.arrows[k].visible) {
          c.arrows[k].position.copy(at);
          c.arrows[k].setDirection(f.clone().normalize());
          c.arrows[k].setLength(f.length(), Math.min(0.04, 0.4 * f.length()), Math.min(0.025, 0.25 * f.length()));
        }
        c.cones[k].visible = on;
        c.cones[k].position.copy(at);
      }
      const inContact = c.contact[i] === 1;
      c.polygonGroup.visible = inContact && controls.polygon.checked;
      const pos = c.polygon3.geometry.attributes.position;
      for (let k = 0; k < c.corners; k++) {
        pos.setXYZ(k, c.polygon[(i * c.corners + k) * 2], c.polygon[(i * c.corners + k) * 2 + 1], 0.002);
      }
      pos.needsUpdate = true;
      c.polygon3.geometry.computeBoundingSphere();
      c.comDot.position.set(c.com[i * 3], c.com[i * 3 + 1], 0.003);
      c.zmpDot.position.set(c.zmp[i * 2], c.zmp[i * 2 + 1], 0.004);
    }
  }

  // ---------------------------------------------------------------- controls and the clock
  const controls = {
    play: document.getElementById("play"), slider: document.getElementById("time"), label: document.getElementById("clock"),
    speed: document.getElementById("speed"), ghost: document.getElementById("ghost"), simulated: document.getElementById("simulated"),
    forces: document.getElementById("forces"), beside: document.getElementById("beside"),
    cones: document.getElementById("cones"), polygon: document.getElementById("polygon"),
  };
  document.getElementById("title").textContent = S.title;
  document.getElementById("summary").textContent = S.summary + " | " + (S.parts_are === "meshes" ? "the robot's meshes" : "skeleton capsules") +
    (S.motions.initial ? " | ghost: the initial motion" : "") +
    (S.motions.simulated ? " | orange: its replay in MuJoCo" : "") +
    (S.beside ? " | beside it: " + S.beside.label : "") +
    (S.contacts ? " | forces: " + S.contacts.force_scale + " m per body weight, cones: friction mu = " + S.contacts.mu : "");
  if (!S.motions.initial) controls.ghost.parentElement.style.display = "none";
  if (!S.motions.simulated) controls.simulated.parentElement.style.display = "none";
  if (!S.beside) controls.beside.parentElement.style.display = "none";
  else document.getElementById("beside-label").textContent = S.beside.label;
  if (!S.contacts) for (const k of ["forces", "cones", "polygon"]) controls[k].parentElement.style.display = "none";
  const hold = 0.5; // s on the last frame before the loop starts again
  const clock = { playing: true, t: 0, wall: performance.now(), played: 0, ticks: 0 }; // played: seconds, never wrapped
  const hash = /t=([0-9.]+)/.exec(window.location.hash);
  if (hash) { clock.playing = false; clock.t = Math.min(parseFloat(hash[1]), S.duration); }
  controls.slider.max = String(S.duration);
  controls.slider.step = String(S.duration / Math.max(1, S.frames - 1));
  controls.play.addEventListener("click", () => {
    clock.playing = !clock.playing;
    clock.wall = performance.now();
  });
  controls.slider.addEventListener("input", () => { clock.playing = false; clock.t = parseFloat(controls.slider.value); });
  function visibility() {
    if (motions.initial) motions.initial.group.visible = controls.ghost.checked;
    if (motions.simulated) motions.simulated.group.visible = controls.simulated.checked;
    if (beside) beside.group.visible = controls.beside.checked;
    if (contacts) {
      contacts.arrowGroup.visible = controls.forces.checked;
      contacts.coneGroup.visible = controls.cones.checked;
    }
  }
  for (const k of ["ghost", "simulated", "beside", "forces", "cones", "polygon"]) controls[k].addEventListener("change", visibility);
  visibility();

  function resize() {
    const w = window.innerWidth, h = window.innerHeight;
    renderer.setSize(w, h);
    camera.aspect = w / h;
    camera.updateProjectionMatrix();
  }
  window.addEventListener("resize", resize);
  resize();
  placeCamera();

  // what the contact layer shows now, for a test in a browser: per point its name, whether its arrow and cone
  // are drawn, where (m) and the arrow's length (m)
  function contactsShown() {
    const r = (x) => Math.round(x * 1e4) / 1e4;
    return contacts.arrows.map((a, k) => ({ name: S.contacts.names[k], arrow: a.visible && contacts.arrowGroup.visible,
      cone: contacts.cones[k].visible && contacts.coneGroup.visible, at: contacts.cones[k].position.toArray().map(r),
      length: r(contacts.lengths[k]) }));
  }

  // paused, the page draws again only after an input (orbit, slider, check boxes, resize): no redraws of a still
  let dirty = true;
  for (const ev of ["pointerdown", "pointermove", "wheel", "input", "change", "click", "keydown", "resize"]) {
    window.addEventListener(ev, () => { dirty = true; }, { capture: true, passive: true });
  }

  function loop(now) {
    if (!clock.playing && !dirty) { clock.wall = now; requestAnimationFrame(loop); return; }
    dirty = false;
    if (clock.playing) {
      const step = (now - clock.wall) / 1000 * parseFloat(controls.speed.value);
      clock.t += step;
      clock.played += step;
      if (clock.t > S.duration + hold) clock.t = 0;
    }
    clock.wall = now;
    const t = Math.min(clock.t, S.duration);
    const i = frameAt(t);
    pose(i);
    controls.slider.value = String(t);
    controls.label.textContent = "t = " + times[i].toFixed(2) + " s";
    controls.play.textContent = clock.playing ? "pause" : "play";
    renderer.render(scene, camera);
    document.body.dataset.frame = String(i);
    document.body.dataset.time = times[i].toFixed(3);
    document.body.dataset.played = clock.played.toFixed(3);
    document.body.dataset.ticks = String(++clock.ticks);
    if (contacts) document.body.dataset.contacts = JSON.stringify(contactsShown());
    if (beside) document.body.dataset.beside = String(beside.objects.length) + (beside.group.visible ? " shown" : " hidden");
    requestAnimationFrame(loop);
  }
  requestAnimationFrame((now) => { clock.wall = now; loop(now); });
  if (status) status.textContent = "";
})();
