// The client's types to haptic.v1 messages in protobuf's JSON mapping and back, as the C++ SDK's
// sdk/src/conversions.cpp converts them to and from protobuf (a wall is a half-space whose pose
// is its point; an unset quaternion is identity; dynamics only when given).
using System;
using System.Collections.Generic;

namespace Hapticd
{
    internal static class Conversions
    {
        private static readonly string[] Laws = { "VELOCITY", "BACKWARD_DIFFERENCE", "EXACT_ZOH", "TUSTIN" };
        private static readonly string[] DistanceKinds = { "POINT", "LINE", "PLANE", "SPHERE" };
        private static readonly string[] PotentialKinds = { "POLYNOMIAL", "KHATIB" };

        /// <summary>An enum's proto name, or HapticException(InvalidArgument) naming the field
        /// ("object.wall.impedance.law: 9 is not one of 0..3"), as the C API says it.</summary>
        private static string EnumName(string[] names, int value, string field, string call)
        {
            if (value < 0 || value >= names.Length)
            {
                throw new HapticException(ErrorCode.InvalidArgument, call + ": " + field + ": " + value + " is not one of 0.." + (names.Length - 1));
            }
            return names[value];
        }

        private static int EnumValue(string[] names, object value)
        {
            if (value is double) return (int)(double)value;
            int i = Array.IndexOf(names, value as string);
            return i < 0 ? 0 : i;
        }

        internal static JsonObject V(Vec3 v) { return new JsonObject().Add("x", v.X).Add("y", v.Y).Add("z", v.Z); }
        internal static JsonObject Q(Quaternion q) { return new JsonObject().Add("w", q.W).Add("x", q.X).Add("y", q.Y).Add("z", q.Z); }
        internal static Vec3 V(JsonObject o) { return new Vec3(o.Double("x"), o.Double("y"), o.Double("z")); }
        internal static Quaternion Q(JsonObject o) { return new Quaternion(o.Double("w"), o.Double("x"), o.Double("y"), o.Double("z")); }
        /// <summary>An orientation read back: identity when unset (types.proto).</summary>
        private static Quaternion Orientation(JsonObject parent, string name)
        {
            return parent.Has(name) ? Q(parent.Object(name)) : Quaternion.Identity;
        }
        private static JsonObject PoseJson(Pose p) { return new JsonObject().Add("position", V(p.Position)).Add("orientation", Q(p.Orientation)); }
        private static Pose PoseOf(JsonObject obj)
        {
            var pose = obj.Object("pose");
            return new Pose(V(pose.Object("position")), Orientation(pose, "orientation"));
        }

        private static JsonObject ImpedanceJson(Impedance i, string path, string call)
        {
            return new JsonObject().Add("stiffness", i.Stiffness).Add("damping", i.Damping)
                .Add("static_friction", i.StaticFriction).Add("dynamic_friction", i.DynamicFriction)
                .Add("law", EnumName(Laws, (int)i.Law, path + ".impedance.law", call)).Add("mass", i.Mass)
                .Add("transparency_optimal_damping", i.TransparencyOptimalDamping).Add("virtual_coupling", i.VirtualCoupling);
        }

        private static Impedance ImpedanceOf(JsonObject o)
        {
            return new Impedance
            {
                Stiffness = o.Double("stiffness"), Damping = o.Double("damping"), StaticFriction = o.Double("static_friction"),
                DynamicFriction = o.Double("dynamic_friction"), Mass = o.Double("mass"), Law = (ImpedanceLaw)EnumValue(Laws, o.Get("law")),
                TransparencyOptimalDamping = o.Bool("transparency_optimal_damping"), VirtualCoupling = o.Bool("virtual_coupling"),
            };
        }

        private static JsonObject DistanceJson(Distance d, string path, string call)
        {
            return new JsonObject().Add("kind", EnumName(DistanceKinds, (int)d.Kind, path + ".kind", call))
                .Add("origin", V(d.Origin)).Add("axis", V(d.Axis)).Add("radius", d.Radius);
        }

        private static Distance DistanceOf(JsonObject o)
        {
            return new Distance { Kind = (DistanceKind)EnumValue(DistanceKinds, o.Get("kind")), Origin = V(o.Object("origin")),
                                  Axis = V(o.Object("axis")), Radius = o.Double("radius") };
        }

        /// <summary>An object: pose, impedance, dynamics (when given), sharing, then its shape.</summary>
        private static JsonObject ObjectJson(Pose pose, Impedance impedance, Dynamics dynamics, bool shared, bool acrossSites,
                                             string shape, JsonObject shapeJson, string path, string call)
        {
            var o = new JsonObject().Add("pose", PoseJson(pose)).Add("impedance", ImpedanceJson(impedance, path, call));
            if (dynamics.Mass != 0.0 || dynamics.Damping != 0.0)
            {
                o.Add("dynamics", new JsonObject().Add("mass", dynamics.Mass).Add("damping", dynamics.Damping));
            }
            return o.Add("shared", shared).Add("across_sites", acrossSites).Add(shape, shapeJson);
        }

        private static JsonObject FieldJson(bool acrossSites, string kind, JsonObject kindJson)
        {
            return new JsonObject().Add("across_sites", acrossSites).Add(kind, kindJson);
        }

        /// <summary>A spec as a haptic.v1 Object (isObject) or Field; InvalidArgument naming
        /// `where` for something that is not a spec.</summary>
        internal static JsonObject ToProto(object spec, out bool isObject, string call, string where)
        {
            isObject = true;
            var none = new Dynamics();
            if (spec is WallSpec)
            {
                var s = (WallSpec)spec;
                return ObjectJson(Pose.At(s.Point), s.Impedance, none, s.Shared, s.AcrossSites, "half_space",
                                  new JsonObject().Add("normal", V(s.Normal)), "object.wall", call);
            }
            if (spec is SphereSpec)
            {
                var s = (SphereSpec)spec;
                // A sphere's pose has no orientation (the C++ SDK sets the position alone).
                var o = new JsonObject().Add("pose", new JsonObject().Add("position", V(s.Center)))
                    .Add("impedance", ImpedanceJson(s.Impedance, "object.sphere", call));
                if (s.Dynamics.Mass != 0.0 || s.Dynamics.Damping != 0.0)
                {
                    o.Add("dynamics", new JsonObject().Add("mass", s.Dynamics.Mass).Add("damping", s.Dynamics.Damping));
                }
                return o.Add("shared", s.Shared).Add("across_sites", s.AcrossSites).Add("sphere", new JsonObject().Add("radius", s.Radius));
            }
            if (spec is BoxSpec)
            {
                var s = (BoxSpec)spec;
                return ObjectJson(s.Pose, s.Impedance, s.Dynamics, s.Shared, s.AcrossSites, "box",
                                  new JsonObject().Add("half_extents", V(s.HalfExtents)), "object.box", call);
            }
            if (spec is CapsuleSpec)
            {
                var s = (CapsuleSpec)spec;
                return ObjectJson(s.Pose, s.Impedance, s.Dynamics, s.Shared, s.AcrossSites, "capsule",
                                  new JsonObject().Add("radius", s.Radius).Add("half_length", s.HalfLength), "object.capsule", call);
            }
            if (spec is TangentPlaneSpec)
            {
                var s = (TangentPlaneSpec)spec;
                return ObjectJson(s.Pose, s.Impedance, none, false, s.AcrossSites, "tangent_plane",
                                  new JsonObject().Add("normal", V(s.Normal)).Add("reference", V(s.Reference))
                                      .Add("tangential_stiffness", s.TangentialStiffness).Add("tangential_damping", s.TangentialDamping),
                                  "object.tangent_plane", call);
            }
            if (spec is MeshSpec)
            {
                var s = (MeshSpec)spec;
                var vertices = new List<object>();
                foreach (var v in s.Vertices ?? new Vec3[0]) vertices.Add(V(v));
                var indices = new List<object>();
                foreach (var i in s.Indices ?? new uint[0]) indices.Add(i);
                return ObjectJson(s.Pose, s.Impedance, none, s.Shared, s.AcrossSites, "mesh",
                                  new JsonObject().Add("vertices", vertices).Add("indices", indices), "object.mesh", call);
            }
            isObject = false;
            if (spec is SpringFieldSpec)
            {
                var s = (SpringFieldSpec)spec;
                return FieldJson(s.AcrossSites, "spring_to_point", new JsonObject().Add("anchor", V(s.Anchor))
                    .Add("stiffness", s.Stiffness).Add("damping", s.Damping).Add("max_force", s.MaxForce));
            }
            if (spec is DistanceSpringSpec)
            {
                var s = (DistanceSpringSpec)spec;
                return FieldJson(s.AcrossSites, "spring", new JsonObject().Add("anchor", DistanceJson(s.Anchor, "field.distance_spring.anchor", call))
                    .Add("stiffness", s.Stiffness).Add("damping", s.Damping).Add("max_force", s.MaxForce));
            }
            if (spec is PotentialFieldSpec)
            {
                var s = (PotentialFieldSpec)spec;
                return FieldJson(s.AcrossSites, "potential", new JsonObject()
                    .Add("distance", DistanceJson(s.Distance, "field.potential.distance", call))
                    .Add("kind", EnumName(PotentialKinds, (int)s.Kind, "field.potential.kind", call)).Add("order", s.Order)
                    .Add("gain", s.Gain).Add("offset", s.Offset).Add("influence_distance", s.InfluenceDistance)
                    .Add("min_distance", s.MinDistance).Add("gradient", s.CentralDifferences ? "CENTRAL_DIFFERENCE" : "ANALYTIC"));
            }
            if (spec is LinearFieldSpec)
            {
                var s = (LinearFieldSpec)spec;
                return FieldJson(s.AcrossSites, "linear", new JsonObject().Add("origin", V(s.Origin)).Add("force", V(s.Force))
                    .Add("jacobian", new List<object> { V(s.JacobianRow0), V(s.JacobianRow1), V(s.JacobianRow2) })
                    .Add("radius", s.Radius).Add("fade_width", s.FadeWidth));
            }
            if (spec is ViscousFieldSpec)
            {
                var s = (ViscousFieldSpec)spec;
                return FieldJson(s.AcrossSites, "viscous", new JsonObject().Add("damping", s.Damping).Add("center", V(s.Center))
                    .Add("radius", s.Radius).Add("fade_width", s.FadeWidth));
            }
            if (spec is DetentFieldSpec)
            {
                var s = (DetentFieldSpec)spec;
                return FieldJson(s.AcrossSites, "detent", new JsonObject().Add("distance", DistanceJson(s.Distance, "field.detent.distance", call))
                    .Add("depth", s.Depth).Add("radius", s.Radius).Add("rim_height", s.RimHeight).Add("rim_width", s.RimWidth));
            }
            if (spec is OrientationSpringSpec)
            {
                var s = (OrientationSpringSpec)spec;
                return FieldJson(s.AcrossSites, "orientation_spring", new JsonObject().Add("target", Q(s.Target))
                    .Add("stiffness", s.Stiffness).Add("damping", s.Damping).Add("max_torque", s.MaxTorque)
                    .Add("law", EnumName(Laws, (int)s.Law, "field.orientation_spring.law", call)));
            }
            if (spec is OrientationDetentSpec)
            {
                var s = (OrientationDetentSpec)spec;
                return FieldJson(s.AcrossSites, "orientation_detent", new JsonObject().Add("target", Q(s.Target))
                    .Add("depth", s.Depth).Add("radius", s.Radius).Add("rim_height", s.RimHeight).Add("rim_width", s.RimWidth)
                    .Add("damping", s.Damping));
            }
            throw new HapticException(ErrorCode.InvalidArgument, call + ": " + where + ": " +
                (spec == null ? "is null" : spec.GetType().Name + " is not an object or field spec"));
        }

        /// <summary>An Object message as the spec it was made from (sdk/src/conversions.cpp's
        /// from_proto: a half-space's normal is turned by its pose into W).</summary>
        internal static object ObjectSpecOf(JsonObject o)
        {
            var impedance = ImpedanceOf(o.Object("impedance"));
            var dynamics = o.Has("dynamics") ? new Dynamics(o.Object("dynamics").Double("mass"), o.Object("dynamics").Double("damping")) : new Dynamics();
            bool shared = o.Bool("shared"), across = o.Bool("across_sites");
            if (o.Has("sphere"))
            {
                return new SphereSpec { Center = V(o.Object("pose").Object("position")), Radius = o.Object("sphere").Double("radius"),
                                        Impedance = impedance, Dynamics = dynamics, Shared = shared, AcrossSites = across };
            }
            if (o.Has("box"))
            {
                return new BoxSpec { Pose = PoseOf(o), HalfExtents = V(o.Object("box").Object("half_extents")), Impedance = impedance,
                                     Dynamics = dynamics, Shared = shared, AcrossSites = across };
            }
            if (o.Has("capsule"))
            {
                var c = o.Object("capsule");
                return new CapsuleSpec { Pose = PoseOf(o), Radius = c.Double("radius"), HalfLength = c.Double("half_length"),
                                         Impedance = impedance, Dynamics = dynamics, Shared = shared, AcrossSites = across };
            }
            if (o.Has("mesh"))
            {
                var m = o.Object("mesh");
                var vertices = new List<Vec3>();
                foreach (var v in m.Array("vertices")) vertices.Add(V(v as JsonObject ?? new JsonObject()));
                var indices = new List<uint>();
                foreach (var i in m.Array("indices")) indices.Add((uint)Json.ToU64(i));
                return new MeshSpec { Pose = PoseOf(o), Vertices = vertices.ToArray(), Indices = indices.ToArray(), Impedance = impedance,
                                      Shared = shared, AcrossSites = across };
            }
            if (o.Has("tangent_plane"))
            {
                var t = o.Object("tangent_plane");
                return new TangentPlaneSpec { Pose = PoseOf(o), Normal = V(t.Object("normal")), Reference = V(t.Object("reference")),
                                              TangentialStiffness = t.Double("tangential_stiffness"),
                                              TangentialDamping = t.Double("tangential_damping"), Impedance = impedance, AcrossSites = across };
            }
            var pose = PoseOf(o);
            return new WallSpec { Point = pose.Position, Normal = Rotate(pose.Orientation, V(o.Object("half_space").Object("normal"))),
                                  Impedance = impedance, Shared = shared, AcrossSites = across };
        }

        /// <summary>v turned by the unit quaternion q (v' = q v q*).</summary>
        private static Vec3 Rotate(Quaternion q, Vec3 v)
        {
            var t = new Vec3(2.0 * (q.Y * v.Z - q.Z * v.Y), 2.0 * (q.Z * v.X - q.X * v.Z), 2.0 * (q.X * v.Y - q.Y * v.X));
            return new Vec3(v.X + q.W * t.X + (q.Y * t.Z - q.Z * t.Y), v.Y + q.W * t.Y + (q.Z * t.X - q.X * t.Z),
                            v.Z + q.W * t.Z + (q.X * t.Y - q.Y * t.X));
        }

        internal static object FieldSpecOf(JsonObject f)
        {
            bool across = f.Bool("across_sites");
            if (f.Has("spring"))
            {
                var s = f.Object("spring");
                return new DistanceSpringSpec { Anchor = DistanceOf(s.Object("anchor")), Stiffness = s.Double("stiffness"),
                                                Damping = s.Double("damping"), MaxForce = s.Double("max_force"), AcrossSites = across };
            }
            if (f.Has("potential"))
            {
                var p = f.Object("potential");
                return new PotentialFieldSpec { Distance = DistanceOf(p.Object("distance")), Kind = (PotentialKind)EnumValue(PotentialKinds, p.Get("kind")),
                                                Order = p.U32("order"), Gain = p.Double("gain"), Offset = p.Double("offset"),
                                                InfluenceDistance = p.Double("influence_distance"), MinDistance = p.Double("min_distance"),
                                                CentralDifferences = p.String("gradient") == "CENTRAL_DIFFERENCE" || p.Get("gradient") is double && (double)p.Get("gradient") == 1.0,
                                                AcrossSites = across };
            }
            if (f.Has("linear"))
            {
                var l = f.Object("linear");
                var rows = l.Array("jacobian");
                Func<int, Vec3> row = i => i < rows.Count ? V(rows[i] as JsonObject ?? new JsonObject()) : new Vec3();
                return new LinearFieldSpec { Origin = V(l.Object("origin")), Force = V(l.Object("force")), JacobianRow0 = row(0),
                                             JacobianRow1 = row(1), JacobianRow2 = row(2), Radius = l.Double("radius"),
                                             FadeWidth = l.Double("fade_width"), AcrossSites = across };
            }
            if (f.Has("viscous"))
            {
                var v = f.Object("viscous");
                return new ViscousFieldSpec { Damping = v.Double("damping"), Center = V(v.Object("center")), Radius = v.Double("radius"),
                                              FadeWidth = v.Double("fade_width"), AcrossSites = across };
            }
            if (f.Has("detent"))
            {
                var d = f.Object("detent");
                return new DetentFieldSpec { Distance = DistanceOf(d.Object("distance")), Depth = d.Double("depth"), Radius = d.Double("radius"),
                                             RimHeight = d.Double("rim_height"), RimWidth = d.Double("rim_width"), AcrossSites = across };
            }
            if (f.Has("orientation_spring"))
            {
                var s = f.Object("orientation_spring");
                return new OrientationSpringSpec { Target = Orientation(s, "target"), Stiffness = s.Double("stiffness"), Damping = s.Double("damping"),
                                                   MaxTorque = s.Double("max_torque"), Law = (ImpedanceLaw)EnumValue(Laws, s.Get("law")),
                                                   AcrossSites = across };
            }
            if (f.Has("orientation_detent"))
            {
                var d = f.Object("orientation_detent");
                return new OrientationDetentSpec { Target = Orientation(d, "target"), Depth = d.Double("depth"), Radius = d.Double("radius"),
                                                   RimHeight = d.Double("rim_height"), RimWidth = d.Double("rim_width"),
                                                   Damping = d.Double("damping"), AcrossSites = across };
            }
            var p2 = f.Object("spring_to_point");
            return new SpringFieldSpec { Anchor = V(p2.Object("anchor")), Stiffness = p2.Double("stiffness"), Damping = p2.Double("damping"),
                                         MaxForce = p2.Double("max_force"), AcrossSites = across };
        }

        internal static StabilityReport StabilityOf(JsonObject ref_, bool present)
        {
            var s = ref_;
            return new StabilityReport
            {
                Available = present, ColgateMinDamping = s.Double("colgate_min_damping"), DeviceMass = s.Double("device_mass"),
                DeviceDamping = s.Double("device_damping"), MaxStableStiffness = s.Double("max_stable_stiffness"),
                MaxPoleMagnitude = s.Double("max_pole_magnitude"), ChosenDamping = s.Double("chosen_damping"),
                ChosenStiffness = s.Double("chosen_stiffness"), Passive = s.Bool("passive"), DeviceKnown = s.Bool("device_known"),
                Stable = s.Bool("stable"), RobustlyStable = s.Bool("robustly_stable"), Warning = s.String("warning"),
            };
        }

        internal static DeviceInfo DeviceInfoOf(JsonObject d)
        {
            var c = d.Object("capabilities");
            var caps = Capabilities.None;
            string[] names = { "gravity", "brakes", "flexible_modes", "friction", "force_sensor", "quantized_position",
                               "state_estimator", "disturbance_observer", "orientation", "torque" };
            for (int i = 0; i < names.Length; ++i) if (c.Bool(names[i])) caps |= (Capabilities)(1u << i);
            return new DeviceInfo
            {
                Name = d.String("name"), Model = d.String("model"), Capabilities = caps, Dof = d.U32("dof"),
                WorkspaceMin = V(d.Object("workspace_min")), WorkspaceMax = V(d.Object("workspace_max")), MaxForce = d.Double("max_force"),
                LoopRateHz = d.Double("loop_rate_hz"), MaxTorque = d.Double("max_torque"), Simulated = d.Bool("simulated"),
                Buttons = d.U32("buttons"),
            };
        }

        /// <summary>A Step reply's ToolState as a State (sequence 0: it did not come as a datagram).</summary>
        internal static State StateOf(JsonObject t, long receivedAtNs)
        {
            var s = new State
            {
                Tick = t.U64("tick"), ServerTime = t.Double("server_time_s"), Position = V(t.Object("position")),
                Velocity = V(t.Object("velocity")), Force = V(t.Object("force")), Proxy = V(t.Object("proxy")),
                ContactCount = t.U32("contact_count"), Flags = (StateFlags)t.U32("flags"), Buttons = t.U32("buttons"),
                Orientation = Quaternion.Identity, ReceivedAtNs = receivedAtNs,
            };
            if (t.Has("orientation"))
            {
                s.HasOrientation = true;
                s.Orientation = Q(t.Object("orientation"));
                s.Torque = V(t.Object("torque"));
            }
            return s;
        }

        private static readonly string[] OperatorModes = { "NONE", "FOLLOW_TARGET", "APPLY_FORCE" };
        private static readonly string[] Grips = { "CUSTOM", "LOOSE", "TIGHT" };
        private static readonly string[] PathShapes = { "FIXED", "LINE", "SINE" };
        private static readonly string[] ProfileShapes = { "CONSTANT", "STEP", "RAMP", "SINE", "RECORDED" };

        internal static JsonObject OperatorJson(OperatorInput input)
        {
            const string call = "SetOperator";
            var samples = new List<object>();
            foreach (var v in input.ProfileSamples ?? new Vec3[0]) samples.Add(V(v));
            return new JsonObject()
                .Add("mode", EnumName(OperatorModes, (int)input.Mode, "input.mode", call)).Add("target", V(input.Target))
                .Add("stiffness", input.Stiffness).Add("damping", input.Damping).Add("force", V(input.Force)).Add("mass", input.Mass)
                .Add("grip", EnumName(Grips, (int)input.Grip, "input.grip", call))
                .Add("trajectory", new JsonObject().Add("shape", EnumName(PathShapes, (int)input.PathShape, "input.path_shape", call))
                    .Add("end", V(input.PathEnd)).Add("duration_s", input.PathDurationS).Add("amplitude", V(input.PathAmplitude))
                    .Add("frequency_hz", input.PathFrequencyHz))
                .Add("profile", new JsonObject().Add("shape", EnumName(ProfileShapes, (int)input.ProfileShape, "input.profile_shape", call))
                    .Add("start_s", input.ProfileStartS).Add("rise_s", input.ProfileRiseS).Add("frequency_hz", input.ProfileFrequencyHz)
                    .Add("offset", V(input.ProfileOffset)).Add("samples", samples).Add("sample_period_s", input.ProfileSamplePeriodS)
                    .Add("repeat", input.ProfileRepeat));
        }

        private static readonly string[] EventKinds = { "KIND_UNSPECIFIED", "SESSION_OPENED", "SESSION_CLOSED", "LEASE_EXPIRED",
                                                        "SCENE_CHANGED", "FORCE_FAULT", "WATCH_STARTED", "DEVICE_FAULT", "RESET" };

        internal static Event EventOf(JsonObject e)
        {
            return new Event { Kind = (EventKind)EnumValue(EventKinds, e.Get("kind")), SessionId = e.U64("session_id"),
                               ItemId = e.U64("item_id"), ServerTime = e.Double("server_time_s"), Message = e.String("message") };
        }

        private static readonly string[] Roles = { "ROLE_UNSPECIFIED", "OBSERVER", "CONTROLLER", "ADMIN" };

        internal static SessionSummary SessionOf(JsonObject s)
        {
            return new SessionSummary { SessionId = s.U64("session_id"), ClientName = s.String("client_name"), Peer = s.String("peer"),
                                        TokenName = s.String("token_name"), DeviceIndex = s.U32("device_index"),
                                        Role = (Role)EnumValue(Roles, s.Get("role")), OpenedTime = s.Double("opened_s") };
        }

        internal static RecordingStatus RecordingOf(JsonObject r)
        {
            return new RecordingStatus { Path = r.String("path"), StartTick = r.U64("start_tick"), Samples = r.U64("samples"),
                                         SamplesMissed = r.U64("samples_missed"), Changes = r.U64("changes"),
                                         RecordsNotWritten = r.U64("records_not_written"), WriteError = r.String("write_error") };
        }

        internal static Stats StatsOf(JsonObject s)
        {
            var f = s.Object("federation");
            var counters = new StatsCounters
            {
                Sessions = s.U32("sessions"), Ticks = s.U64("ticks"), AchievedRateHz = s.Double("achieved_rate_hz"),
                LatenessP50Us = s.Double("lateness_p50_us"), LatenessP99Us = s.Double("lateness_p99_us"),
                LatenessP999Us = s.Double("lateness_p999_us"), LatenessMaxUs = s.Double("lateness_max_us"),
                LatenessSamples = s.U64("lateness_samples"), WindowS = s.Double("window_s"), Overruns = s.U64("overruns"),
                Objects = s.U32("objects"), Fields = s.U32("fields"), DatagramsSent = s.U64("datagrams_sent"),
                DatagramsReceived = s.U64("datagrams_received"), DatagramsDropped = s.U64("datagrams_dropped"),
                ForceFaults = s.U64("force_faults"), ForceSaturations = s.U64("force_saturations"),
                PassivityActiveTicks = s.U64("passivity_active_ticks"), LeasesExpired = s.U64("leases_expired"),
                DeviceFaults = s.U64("device_faults"), SendDelayP50Us = s.Double("send_delay_p50_us"),
                SendDelayP99Us = s.Double("send_delay_p99_us"), SendDelayP999Us = s.Double("send_delay_p999_us"),
                HeartbeatsRateLimited = s.U64("heartbeats_rate_limited"), DatagramsForeignSource = s.U64("datagrams_foreign_source"),
                PathChallengesSent = s.U64("path_challenges_sent"), SamplesSkipped = s.U64("samples_skipped"),
                ConnectionsRefused = s.U64("connections_refused"), ConnectionsTimedOut = s.U64("connections_timed_out"),
                ConnectionsEvicted = s.U64("connections_evicted"), TlsHandshakesFailed = s.U64("tls_handshakes_failed"),
                ConnectionsOpen = s.U32("connections_open"), HasFederation = s.Has("federation"),
                FederationSamplesPublished = f.U64("samples_published"), FederationSamplesFailed = f.U64("samples_failed"),
                FederationItemsPublished = f.U64("items_published"), FederationItemsApplied = f.U64("items_applied"),
                FederationItemsRefused = f.U64("items_refused"), FederationWrenchesAccepted = f.U64("wrenches_accepted"),
                FederationWrenchesRefused = f.U64("wrenches_refused"),
            };
            var clients = new List<StreamStats>();
            foreach (var item in s.Array("clients"))
            {
                var c = item as JsonObject ?? new JsonObject();
                clients.Add(new StreamStats
                {
                    SessionId = c.U64("session_id"), ClientName = c.String("client_name"), Peer = c.String("peer"),
                    DeviceIndex = c.U32("device_index"), Decimation = c.U32("decimation"), DatagramsSent = c.U64("datagrams_sent"),
                    Heartbeats = c.U64("heartbeats"), StatesReceived = c.U64("states_received"), StatesLost = c.U64("states_lost"),
                    LastHeartbeatAgeS = c.Double("last_heartbeat_age_s"), RoundTripSamples = c.U32("round_trip_samples"),
                    RoundTripP50Us = c.Double("round_trip_p50_us"), RoundTripP99Us = c.Double("round_trip_p99_us"),
                    RoundTripP999Us = c.Double("round_trip_p999_us"),
                });
            }
            var couplings = new List<CouplingStats>();
            foreach (var item in f.Array("couplings"))
            {
                var c = item as JsonObject ?? new JsonObject();
                couplings.Add(new CouplingStats
                {
                    Kind = c.String("kind") == "MASS" ? 1 : 0, Port = c.U32("port"), Remote = c.U64("remote"), Mass = c.U64("mass"),
                    InjectedJ = c.Double("injected_j"), GivenJ = c.Double("given_j"), SentJ = c.Double("sent_j"),
                    ReceivedJ = c.Double("received_j"), ReservoirJ = c.Double("reservoir_j"),
                });
            }
            counters.ClientCount = (uint)clients.Count;
            counters.CouplingCount = (uint)couplings.Count;
            return new Stats { Counters = counters, Clients = clients.ToArray(), Couplings = couplings.ToArray() };
        }
    }
}
