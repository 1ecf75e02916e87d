// The C# binding against a real lockstep hapticd (its address is the first argument; the gtest in
// tests/integration/csharp_test.cpp starts the server and runs this under Mono): the acceptance
// the Python SDK has — every object kind registered and read back, a wall holding a push,
// refusals naming the field, callbacks on another thread with no delegate collected under them —
// and the structs laid out as the C library lays them out.
using System;
using System.Collections.Generic;
using System.Reflection;
using System.Threading;
using Hapticd;

static class ClientTests
{
    static int failures;
    static string currentTest = "";

    static void Check(bool condition, string what)
    {
        if (condition) return;
        failures++;
        Console.Error.WriteLine("FAIL " + currentTest + ": " + what);
    }

    static void Near(double actual, double expected, double tolerance, string what)
    {
        Check(Math.Abs(actual - expected) <= tolerance, what + ": " + actual + " is not within " + tolerance + " of " + expected);
    }

    static HapticException Throws(Action action, string what)
    {
        try { action(); }
        catch (HapticException e) { return e; }
        Check(false, what + ": no HapticException");
        return new HapticException(ErrorCode.Ok, "");
    }

    static Impedance Stiff { get { return new Impedance(1000.0, 1.0); } }

    static List<object> EveryObjectKind()
    {
        var pose = Pose.At(new Vec3(0.3, 0.3, 0.3));
        var wall = WallSpec.Default; wall.Point = new Vec3(0, 0, -0.05); wall.Impedance = Stiff;
        var sphere = SphereSpec.Default; sphere.Center = new Vec3(0.2, 0, 0); sphere.Radius = 0.01; sphere.Impedance = Stiff;
        var box = BoxSpec.Default; box.Pose = pose; box.HalfExtents = new Vec3(0.01, 0.02, 0.03); box.Impedance = Stiff;
        var capsule = CapsuleSpec.Default; capsule.Pose = pose; capsule.Radius = 0.01; capsule.HalfLength = 0.02; capsule.Impedance = Stiff;
        var plane = TangentPlaneSpec.Default; plane.Pose = pose; plane.Normal = new Vec3(0, 1, 0); plane.TangentialStiffness = 50.0; plane.Impedance = Stiff;
        var mesh = new MeshSpec
        {
            Pose = pose,
            Vertices = new[] { new Vec3(0, 0, 0), new Vec3(0.05, 0, 0), new Vec3(0, 0.05, 0), new Vec3(0, 0, 0.05) },
            Indices = new uint[] { 0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3 },
            Impedance = Stiff,
        };
        return new List<object> { wall, sphere, box, capsule, plane, mesh };
    }

    static List<object> EveryFieldKind()
    {
        var spring = SpringFieldSpec.Default; spring.Anchor = new Vec3(0, 0, 0.02); spring.Stiffness = 20.0; spring.MaxForce = 2.0;
        var line = DistanceSpringSpec.Default; line.Anchor.Kind = DistanceKind.Line; line.Anchor.Axis = new Vec3(1, 0, 0); line.Stiffness = 10.0;
        var potential = PotentialFieldSpec.Default; potential.Distance.Origin = new Vec3(0.5, 0, 0); potential.Gain = 10.0; potential.Offset = 0.01;
        var linear = LinearFieldSpec.Default; linear.Origin = new Vec3(0.5, 0.5, 0); linear.Force = new Vec3(0, 0, 0.1); linear.Radius = 0.01; linear.FadeWidth = 0.005;
        var viscous = ViscousFieldSpec.Default; viscous.Damping = 0.5; viscous.Center = new Vec3(0.5, 0.5, 0.5); viscous.Radius = 0.01; viscous.FadeWidth = 0.005;
        var detent = DetentFieldSpec.Default; detent.Distance.Origin = new Vec3(-0.5, 0, 0); detent.Depth = 0.01; detent.Radius = 0.01; detent.RimHeight = 0.001; detent.RimWidth = 0.005;
        var turn = OrientationSpringSpec.Default; turn.Target = new Quaternion(0.5, 0.5, -0.5, 0.5); turn.Stiffness = 0.5; turn.Damping = 0.01; turn.MaxTorque = 0.1; turn.Law = ImpedanceLaw.BackwardDifference;
        var click = OrientationDetentSpec.Default; click.Target = new Quaternion(0, 0, 0, 1); click.Depth = 0.01; click.Radius = 0.2; click.RimHeight = 0.002; click.RimWidth = 0.1; click.Damping = 0.001;
        return new List<object> { spring, line, potential, linear, viscous, detent, turn, click };
    }

    static object AddAny(Client client, object spec)
    {
        if (spec is WallSpec) return client.AddWall((WallSpec)spec);
        if (spec is SphereSpec) return client.AddSphere((SphereSpec)spec);
        if (spec is BoxSpec) return client.AddBox((BoxSpec)spec);
        if (spec is CapsuleSpec) return client.AddCapsule((CapsuleSpec)spec);
        if (spec is TangentPlaneSpec) return client.AddTangentPlane((TangentPlaneSpec)spec);
        if (spec is MeshSpec) return client.AddMesh((MeshSpec)spec);
        if (spec is SpringFieldSpec) return client.AddField((SpringFieldSpec)spec);
        if (spec is DistanceSpringSpec) return client.AddField((DistanceSpringSpec)spec);
        if (spec is PotentialFieldSpec) return client.AddField((PotentialFieldSpec)spec);
        if (spec is LinearFieldSpec) return client.AddField((LinearFieldSpec)spec);
        if (spec is ViscousFieldSpec) return client.AddField((ViscousFieldSpec)spec);
        if (spec is DetentFieldSpec) return client.AddField((DetentFieldSpec)spec);
        if (spec is OrientationSpringSpec) return client.AddField((OrientationSpringSpec)spec);
        return client.AddField((OrientationDetentSpec)spec);
    }

    static string Json(object spec) { return Client.SceneJson(new List<object> { spec }); }

    static State StepAndGet(Client client, uint ticks)
    {
        ulong tick = client.Step(ticks);
        State state;
        Check(client.WaitForTick(tick, out state, 5000) && state.Tick == tick, "wait_for_tick after step");
        return state;
    }

    // The client is managed code alone: no method of the assembly is extern (P/Invoke or an
    // internal call), so Unity's IL2CPP and every platform load it as it is; the defaults are the
    // C++ SDK's (sdk/include/haptic/types.hpp).
    static void TheAssemblyIsManagedAloneWithTheCppSdksDefaults()
    {
        currentTest = "managed";
        var assembly = typeof(Client).Assembly;
        int methods = 0;
        foreach (var type in assembly.GetTypes())
        {
            foreach (var m in type.GetMethods(BindingFlags.Public | BindingFlags.NonPublic | BindingFlags.Instance | BindingFlags.Static | BindingFlags.DeclaredOnly))
            {
                ++methods;
                bool pinvoke = (m.Attributes & MethodAttributes.PinvokeImpl) != 0;
                bool internalCall = (m.GetMethodImplementationFlags() & MethodImplAttributes.InternalCall) != 0;
                Check(!pinvoke && !internalCall, type.Name + "." + m.Name + " is extern");
            }
        }
        Check(methods > 100, "the assembly's methods were read: " + methods);
        foreach (var reference in assembly.GetReferencedAssemblies())
        {
            Check(reference.Name == "mscorlib" || reference.Name == "System" || reference.Name == "System.Core" || reference.Name == "netstandard",
                  "references only the base library: " + reference.Name);
        }
        Check(WallSpec.Default.Normal.Z == 1.0 && BoxSpec.Default.Pose.Orientation.W == 1.0, "defaults");
        Check(PotentialFieldSpec.Default.Order == 2 && DistanceSpringSpec.Default.Anchor.Axis.Z == 1.0, "potential order, distance axis");
        Check(OrientationSpringSpec.Default.Target.W == 1.0 && TangentPlaneSpec.Default.Normal.Z == 1.0, "orientation target, plane normal");
        var config = new ClientConfig();
        Check(config.ServerAddress == "127.0.0.1:8081" && config.Reconnect && config.StateDecimation == 1 && config.RpcTimeoutMs == 2000 &&
              config.HeartbeatPeriodMs == 100 && config.ClientName == "haptic-client", "config defaults");
        var e = Throws(() => new Client(new ClientConfig { ServerAddress = "no port" }), "a bad address");
        Check(e.Code == ErrorCode.InvalidArgument && e.Message.StartsWith("ClientConfig: ServerAddress: 'no port'"), e.Message);
        e = Throws(() => new Client(new ClientConfig { ServerAddress = "10.1.2.3:8081", Token = "secret-token-0123456789" }), "a token in clear");
        Check(e.Code == ErrorCode.InvalidArgument && e.Message.StartsWith("ClientConfig: token: would be sent in clear"), e.Message);
    }

    static void AWallHoldsAPush(Client client)
    {
        currentTest = "wall";
        client.SetOperator(OperatorInput.Push(new Vec3(0, 0, -5.0)));
        var spec = WallSpec.Default;
        spec.Impedance = Stiff;
        using (var wall = client.AddWall(spec))
        {
            Check(wall.Owned && wall.Id > 0, "owned with an id");
            Check(wall.Stability.DeviceKnown && wall.Stability.Available, "stability report");
            var state = StepAndGet(client, 3000);
            // At rest the wall balances the push: 5 mm deep, 5 N up.
            Check(state.ContactCount == 1, "in contact");
            Near(state.Position.Z, -0.005, 1e-6, "depth");
            Near(state.Force.Z, 5.0, 1e-3, "force");
        }
        var after = StepAndGet(client, 100);
        Check(after.Force.Z == 0.0 && after.ContactCount == 0, "removed by Dispose: force ramped out");
        client.SetOperator(OperatorInput.Release());
    }

    static void EveryKindRegistersReadsBackAndUpdates(Client client)
    {
        currentTest = "every kind";
        var objectSpecs = EveryObjectKind();
        var fieldSpecs = EveryFieldKind();
        var objects = new List<ObjectHandle>();
        var fields = new List<FieldHandle>();
        foreach (var spec in objectSpecs) objects.Add((ObjectHandle)AddAny(client, spec));
        foreach (var spec in fieldSpecs) fields.Add((FieldHandle)AddAny(client, spec));
        var scene = client.Scene();
        Check(scene.Objects.Count == 6 && scene.Fields.Count == 8, "counts");
        for (int i = 0; i < scene.Objects.Count && i < 6; ++i)
        {
            Check(scene.ObjectIds[i] == objects[i].Id, "object id " + i);
            Check(scene.Objects[i].GetType() == objectSpecs[i].GetType(), "object kind " + i);
            Check(Json(scene.Objects[i]) == Json(objectSpecs[i]), "object " + i + " as given: " + Json(scene.Objects[i]));
            Check(scene.ObjectSessions[i] == client.SessionId, "object session " + i);
        }
        for (int i = 0; i < scene.Fields.Count && i < 8; ++i)
        {
            Check(scene.FieldIds[i] == fields[i].Id, "field id " + i);
            Check(scene.Fields[i].GetType() == fieldSpecs[i].GetType(), "field kind " + i);
            Check(Json(scene.Fields[i]) == Json(fieldSpecs[i]), "field " + i + " as given: " + Json(scene.Fields[i]));
        }
        var mesh = scene.Objects.Count > 5 ? scene.Objects[5] as MeshSpec : null;
        Check(mesh != null && mesh.Vertices.Length == 4 && mesh.Indices.Length == 12 && mesh.Vertices[1].X == 0.05, "mesh read back");
        Check(fields[6].Stability.Available && !fields[0].Stability.Available, "an orientation spring's report alone");

        var sphere = (SphereSpec)objectSpecs[1];
        sphere.Radius = 0.03;
        objects[1].Update(sphere);
        var viscous = (ViscousFieldSpec)fieldSpecs[4];
        viscous.Damping = 1.5;
        fields[4].Update(viscous);
        var turn = OrientationSpringSpec.Default;
        turn.Stiffness = 0.2;
        fields[7].Update(turn);  // a detent becomes a spring
        scene = client.Scene();
        Check(((SphereSpec)scene.Objects[1]).Radius == 0.03, "sphere updated");
        Check(((ViscousFieldSpec)scene.Fields[4]).Damping == 1.5, "viscous updated");
        Check(scene.Fields[7] is OrientationSpringSpec && Json(scene.Fields[7]) == Json(turn), "detent became a spring");
        foreach (var o in objects) o.Remove();
        foreach (var f in fields) f.Dispose();
        scene = client.Scene();
        Check(scene.Objects.Count == 0 && scene.Fields.Count == 0, "all removed");
    }

    static void RefusalsNameTheFieldAndChangeNothing(Client client)
    {
        currentTest = "refusals";
        var spec = SphereSpec.Default;
        spec.Center = new Vec3(0, 0, 0.1);
        spec.Radius = 0.01;
        spec.Impedance = Stiff;
        using (var sphere = client.AddSphere(spec))
        {
            var bad = spec;
            bad.Radius = -1.0;
            var e = Throws(() => sphere.Update(bad), "negative radius");
            Check(e.Code == ErrorCode.InvalidArgument, "code " + e.Code);
            Check(e.Message.Contains("object.sphere.radius"), "message names the field: " + e.Message);
            Check(((SphereSpec)client.Scene().Objects[0]).Radius == 0.01, "the sphere is as it was");

            var nanWall = WallSpec.Default;
            nanWall.Normal = new Vec3(0, 0, double.NaN);
            e = Throws(() => client.AddWall(nanWall), "NaN normal");
            Check(e.Message.StartsWith("CreateObject: object.half_space.normal"), "NaN normal named: " + e.Message);
            var lawWall = WallSpec.Default;
            lawWall.Impedance.Law = (ImpedanceLaw)9;
            e = Throws(() => client.AddWall(lawWall), "law out of range");
            Check(e.Message == "CreateObject: object.wall.impedance.law: 9 is not one of 0..3", e.Message);
            // A scene with one bad item is refused whole, naming it; the scene before stays.
            var items = new List<object> { WallSpec.Default, bad };
            e = Throws(() => client.ApplyScene(items), "bad scene");
            Check(e.Message.Contains("scene.objects[1]"), "scene item named: " + e.Message);
            e = Throws(() => client.ApplyScene(new List<object> { "a wall" }), "not a spec");
            Check(e.Message == "ApplyScene: items[0]: String is not an object or field spec", e.Message);
            Check(client.Scene().Objects.Count == 1, "the scene before stays");
        }
        var unreachable = new ClientConfig { ServerAddress = "127.0.0.1:1", RpcTimeoutMs = 200, Reconnect = false };
        var refused = Throws(() => new Client(unreachable), "unreachable server");
        Check(refused.Code == ErrorCode.Connection, "connection error: " + refused.Code);
    }

    static void AScenesAppliesWholeAndReadsBack(Client client)
    {
        currentTest = "scene";
        var items = new List<object>();
        items.AddRange(EveryObjectKind());
        items.AddRange(EveryFieldKind());
        var applied = client.ApplyScene(items);
        Check(applied.Objects.Count == 6 && applied.Fields.Count == 8 && applied.Stability.Count == 6, "handles");
        var scene = client.Scene();
        for (int i = 0; i < 6; ++i) Check(scene.ObjectIds[i] == applied.Objects[i].Id && Json(scene.Objects[i]) == Json(items[i]), "scene object " + i);
        for (int i = 0; i < 8; ++i) Check(scene.FieldIds[i] == applied.Fields[i].Id && Json(scene.Fields[i]) == Json(items[6 + i]), "scene field " + i);
        // The same as a scene file (SceneJson writes what ApplySceneFile and hapticd --scene read).
        string file = System.IO.Path.GetTempFileName();
        try
        {
            System.IO.File.WriteAllText(file, Client.SceneJson(items));
            var fromFile = client.ApplySceneFile(file);
            scene = client.Scene();
            Check(fromFile.Objects.Count == 6 && fromFile.Fields.Count == 8 && scene.ObjectIds[0] == fromFile.Objects[0].Id &&
                  Json(scene.Objects[5]) == Json(items[5]) && Json(scene.Fields[7]) == Json(items[13]), "the scene from its file");
            System.IO.File.WriteAllText(file, "{\"objects\": [");
            var e = Throws(() => client.ApplySceneFile(file), "a file that is not JSON");
            Check(e.Code == ErrorCode.InvalidArgument && e.Message.StartsWith("ApplySceneFile: " + file + ": JSON"), e.Message);
            Check(client.Scene().Objects.Count == 6, "the scene before stays");
        }
        finally
        {
            System.IO.File.Delete(file);
        }
        client.ApplyScene(new List<object>());
        Check(client.Scene().Objects.Count == 0, "an empty scene clears it");
        foreach (var o in applied.Objects) o.Dispose();  // stale: nothing to remove (nor the file's)
        foreach (var f in applied.Fields) f.Dispose();
    }

    static void CallbacksArriveOnAnotherThreadAndSurviveCollections(Client client)
    {
        currentTest = "callbacks";
        int caller = Thread.CurrentThread.ManagedThreadId;
        int states = 0, onCaller = 0;
        ulong lastTick = 0;
        var kinds = new List<EventKind>();
        var gate = new object();
        client.OnState(s =>
        {
            lock (gate)
            {
                states++;
                if (Thread.CurrentThread.ManagedThreadId == caller) onCaller++;
                lastTick = s.Tick;
            }
        });
        client.OnEvent(e => { lock (gate) kinds.Add(e.Kind); });
        // Collections while the SDK holds the callbacks: the delegates it calls must stay alive.
        ulong tick = 0;
        for (int round = 0; round < 20; ++round)
        {
            GC.Collect();
            GC.WaitForPendingFinalizers();
            tick = client.Step(50);
        }
        var spec = WallSpec.Default;
        spec.Point = new Vec3(0, 0, -0.5);
        using (client.AddWall(spec)) { }
        for (int i = 0; i < 300; ++i)
        {
            lock (gate) { if (lastTick >= tick && kinds.Contains(EventKind.SceneChanged)) break; }
            State s;
            client.PollState(out s, 10);
        }
        client.OnState(null);
        client.OnEvent(null);
        int seen;
        lock (gate)
        {
            seen = states;
            Check(states > 0 && onCaller == 0, "states " + states + ", on the caller's thread " + onCaller);
            Check(kinds.Contains(EventKind.WatchStarted) && kinds.Contains(EventKind.SceneChanged), "events: " + string.Join(",", kinds));
        }
        client.Step(50);
        Thread.Sleep(50);
        lock (gate) Check(states == seen, "no calls after OnState(null)");
        // A callback that throws is caught and counted; the stream carries on.
        client.OnState(s => { throw new InvalidOperationException("thrown on purpose"); });
        client.Step(20);
        for (int i = 0; i < 100 && client.CallbackExceptions == 0; ++i) Thread.Sleep(10);
        client.OnState(null);
        Check(client.CallbackExceptions > 0, "exceptions counted");
    }

    static void TheRestOfTheSession(Client client)
    {
        currentTest = "session";
        var info = client.DeviceInfo;
        Check(info.Simulated && info.LoopRateHz > 0 && info.Model == "point_mass" && info.Dof == 3, "device " + info.Model);
        Check(client.SessionId > 0 && client.LeaseTimeoutMs > 0 && client.ConnectionState == ConnectionState.Connected, "session");
        var stats = client.Stats();
        Check(stats.Counters.Ticks > 0 && stats.Clients.Length == 1 && stats.Clients[0].ClientName == "csharp-test", "stats");
        var sessions = client.Sessions();
        Check(sessions.Length == 1 && sessions[0].SessionId == client.SessionId, "sessions");
        Check(client.ReceiveCounters.Accepted > 0, "counters");
        Check(client.ServerTimeNow().HasValue, "server time");
        // Energy per item and a pushable body's state, read back over the HTTP face.
        var ball = SphereSpec.Default;
        ball.Center = new Vec3(0.3, 0, 0);
        ball.Radius = 0.01;
        ball.Impedance = Stiff;
        ball.Dynamics = new Dynamics(0.1, 0.5);
        using (var body = client.AddSphere(ball))
        {
            client.Step(10);
            var energy = client.SceneEnergy();
            Check(Array.Exists(energy, x => x.Id == body.Id && x.IsObject && x.SessionId == client.SessionId), "SceneEnergy lists the sphere");
            var bodies = client.ObjectStates();
            Check(Array.Exists(bodies, x => x.Id == body.Id && Math.Abs(x.Position.X - 0.3) < 1e-9), "ObjectStates has the body where it was put");
        }
        var e = Throws(() => client.StartRecording("x.rec"), "no recording_dir");
        Check(e.Code == ErrorCode.FailedPrecondition, "recording refused: " + e.Code);
        // Motion on a path of constant acceleration is exact.
        var a = new State { ServerTime = 1.0, Velocity = new Vec3(0.1, 0, 0) };
        var b = new State { ServerTime = 1.001, Position = new Vec3(0.1 * 0.001 + 0.001 * 0.001, 0, 0), Velocity = new Vec3(0.1 + 0.002, 0, 0) };
        Near(Motion.Predict(a, b, 1.002).X, 0.1 * 0.002 + 0.002 * 0.002, 1e-12, "predict");
        Near(Motion.Interpolate(a, b, 1.0005).X, 0.1 * 0.0005 + 0.0005 * 0.0005, 1e-12, "interpolate");
    }

    // A double exactly, as a C hex float (strtod reads it back bit for bit): Mono's "R" and "G17"
    // do not always round-trip (-7.1266979490496405e-308 came out as ...395e-308), and the test
    // compares the doubles exactly.
    static string R(double v)
    {
        if (double.IsNaN(v)) return "NaN";
        long bits = BitConverter.DoubleToInt64Bits(v);
        string sign = bits < 0 ? "-" : "";
        int exponent = (int)((bits >> 52) & 0x7FF);
        long fraction = bits & 0xFFFFFFFFFFFFFL;
        if (exponent == 0x7FF) return sign + "inf";
        if (exponent == 0) return sign + "0x0." + fraction.ToString("x13") + "p-1022";  // zero and subnormals
        return sign + "0x1." + fraction.ToString("x13") + "p" + (exponent - 1023);
    }

    // Records a session to dir/session.csv while the state callback keeps what
    // it saw, written to dir/seen.csv in the recorder's columns for the test to compare.
    static void TheRecorderWritesWhatTheClientReceived(Client client, string dir)
    {
        currentTest = "recorder";
        var before = client.ReceiveCounters.Accepted;
        var csv = client.Record(new RecorderOptions { Path = dir + "/session.csv" });
        Check(csv.Path == dir + "/session.csv" && csv.EventsPath == dir + "/session.events.csv", "paths " + csv.EventsPath);
        var e = Throws(() => client.Record(new RecorderOptions { Path = dir + "/session.txt" }), "unknown extension");
        Check(e.Code == ErrorCode.InvalidArgument && e.Message.StartsWith("record: path: "), e.Message);
        e = Throws(() => client.Record(new RecorderOptions { Path = dir + "/session.csv" }), "existing file");
        Check(e.Message.Contains("exists"), e.Message);
        // HDF5 is the C++ SDK's library's: refused, naming the format, and no file left behind.
        e = Throws(() => client.Record(new RecorderOptions { Path = dir + "/session.h5" }), "HDF5");
        Check(e.Code == ErrorCode.InvalidArgument && e.Message.StartsWith("record: format: HDF5") && !System.IO.File.Exists(dir + "/session.h5"), e.Message);

        var seen = new List<State>();
        var gate = new object();
        client.OnState(s => { lock (gate) seen.Add(s); });
        var spec = WallSpec.Default;
        spec.Impedance = Stiff;
        var wall = client.AddWall(spec);
        client.SetOperator(OperatorInput.Push(new Vec3(0, 0, -2.0)));
        for (int chunk = 0; chunk < 20; ++chunk)
        {
            if (chunk == 15) wall.Remove();
            ulong last = client.Step(50);
            for (int i = 0; i < 1000; ++i)
            {
                lock (gate) { if (seen.Count > 0 && seen[seen.Count - 1].Tick >= last) break; }
                State ignored;
                client.PollState(out ignored, 5);
            }
        }
        client.OnState(null);
        client.SetOperator(OperatorInput.Release());
        var accepted = client.ReceiveCounters.Accepted - before;
        var csvTotals = csv.Close();
        Check(csvTotals.SamplesReceived == accepted && csvTotals.SamplesWritten == accepted && csvTotals.Dropped == 0 &&
              csvTotals.WriteErrors == 0 && csvTotals.EventsWritten >= 1, "CSV totals " + csvTotals.SamplesWritten + " of " + accepted);
        Check(!csv.Recording && csv.Close().SamplesWritten == csvTotals.SamplesWritten, "closing again gives the totals again");
        using (var file = new System.IO.StreamWriter(dir + "/seen.csv"))
        {
            file.Write("received_ns,arrived_ns,tick,sequence,server_time_s,position_x_m,position_y_m,position_z_m," +
                       "velocity_x_m_s,velocity_y_m_s,velocity_z_m_s,force_x_N,force_y_N,force_z_N,proxy_x_m,proxy_y_m," +
                       "proxy_z_m,contact_count,flags,buttons,age_ns,orientation_w,orientation_x,orientation_y,orientation_z," +
                       "torque_x_Nm,torque_y_Nm,torque_z_Nm\n");
            foreach (var s in seen)
            {
                file.Write(string.Join(",", new[] {
                    s.ReceivedAtNs.ToString(), (s.ArrivedAtNs != 0 ? s.ArrivedAtNs : -1).ToString(), s.Tick.ToString(), s.Sequence.ToString(),
                    R(s.ServerTime), R(s.Position.X), R(s.Position.Y), R(s.Position.Z), R(s.Velocity.X), R(s.Velocity.Y), R(s.Velocity.Z),
                    R(s.Force.X), R(s.Force.Y), R(s.Force.Z), R(s.Proxy.X), R(s.Proxy.Y), R(s.Proxy.Z),
                    s.ContactCount.ToString(), ((uint)s.Flags).ToString(), s.Buttons.ToString(), s.AgeNs.ToString(),
                    R(s.HasOrientation ? s.Orientation.W : double.NaN), R(s.HasOrientation ? s.Orientation.X : double.NaN),
                    R(s.HasOrientation ? s.Orientation.Y : double.NaN), R(s.HasOrientation ? s.Orientation.Z : double.NaN),
                    R(s.HasOrientation ? s.Torque.X : double.NaN), R(s.HasOrientation ? s.Torque.Y : double.NaN),
                    R(s.HasOrientation ? s.Torque.Z : double.NaN) }) + "\n");
            }
        }
        Check(seen.Count > 0, "the callback saw samples");
    }

    // Against a server with TLS, mutual TLS and tokens (csharp_test.cpp's): a client with the CA,
    // its PKCS#12 certificate and the controller's token holds a wall; each thing missing or wrong
    // is refused, saying which. Mono reads RSA certificates only (its X509 classes know no EC keys).
    static void TlsMutualTlsAndTokens(string address, string certs)
    {
        currentTest = "tls";
        const string token = "controller-token-0123456789";
        Func<ClientConfig> good = () => new ClientConfig
        {
            ServerAddress = address, ClientName = "csharp-tls", TlsCaFile = certs + "/ca.pem", TlsCertFile = certs + "/client.p12",
            Token = token, Reconnect = false, RpcTimeoutMs = 5000,
        };
        using (var client = new Client(good()))
        {
            client.SetOperator(OperatorInput.Push(new Vec3(0, 0, -5.0)));
            var spec = WallSpec.Default;
            spec.Impedance = Stiff;
            using (client.AddWall(spec))
            {
                var state = StepAndGet(client, 3000);
                Near(state.Force.Z, 5.0, 1e-3, "the wall holds the push over TLS");
            }
            var kinds = new List<EventKind>();
            var gate = new object();
            client.OnEvent(e => { lock (gate) kinds.Add(e.Kind); });
            for (int i = 0; i < 100; ++i) { lock (gate) if (kinds.Count > 0) break; Thread.Sleep(10); }
            client.OnEvent(null);
            lock (gate) Check(kinds.Contains(EventKind.WatchStarted), "events over wss://");
        }
        var noCertificate = good();
        noCertificate.TlsCertFile = "";
        var e1 = Throws(() => new Client(noCertificate).Dispose(), "no client certificate");
        Check(e1.Code == ErrorCode.Connection, "without a certificate: " + e1.Code + " " + e1.Message);
        var otherCa = good();
        otherCa.TlsCaFile = certs + "/other_ca.pem";
        var e2 = Throws(() => new Client(otherCa).Dispose(), "another CA");
        Check(e2.Code == ErrorCode.Connection && e2.Message.Contains("not signed by the CA in TlsCaFile"), e2.Message);
        var noToken = good();
        noToken.Token = "";
        var e3 = Throws(() => new Client(noToken).Dispose(), "no token");
        Check(e3.Code == ErrorCode.Unauthenticated && e3.Message.StartsWith("OpenSession: "), e3.Code + " " + e3.Message);
        var pemKey = good();
        pemKey.TlsCertFile = certs + "/client.pem";
        pemKey.TlsKeyFile = certs + "/client.key";
        var e4 = Throws(() => new Client(pemKey).Dispose(), "a PEM key");
        Check(e4.Code == ErrorCode.InvalidArgument && e4.Message.StartsWith("ClientConfig: TlsKeyFile: "), e4.Message);
        var plain = good();
        plain.TlsCaFile = "";
        plain.TlsCertFile = "";
        var e5 = Throws(() => new Client(plain).Dispose(), "plain HTTP to the HTTPS face");
        Check(e5.Code == ErrorCode.Connection, "plain HTTP: " + e5.Code + " " + e5.Message);
    }

    // A server restarted on the same ports under a client (csharp_test.cpp restarts it once the
    // ready file is written): the client says Lost, then Resumed with a new session holding its
    // wall and field again, and its stream and calls work there.
    static void AServerRestartIsSurvivedWithEveryItem(string address, string readyFile)
    {
        currentTest = "reconnect";
        var changes = new List<ConnectionChange>();
        var gate = new object();
        using (var client = new Client(new ClientConfig { ServerAddress = address, ClientName = "csharp-survivor", RpcTimeoutMs = 1000 }))
        {
            client.OnConnection(c => { lock (gate) changes.Add(c); });
            var spec = WallSpec.Default;
            spec.Impedance = Stiff;
            var wall = client.AddWall(spec);
            var spring = SpringFieldSpec.Default;
            spring.Anchor = new Vec3(0, 0, 0.05);
            spring.Stiffness = 50.0;
            var field = client.AddField(spring);
            ulong oldSession = client.SessionId;
            // Its recorder's events file takes the connection's changes (this client's own).
            string events = System.IO.Path.GetDirectoryName(readyFile) + "/reconnect.csv";
            var recorder = client.Record(new RecorderOptions { Path = events });
            StepAndGet(client, 20);
            System.IO.File.WriteAllText(readyFile, "ready\n");
            ConnectionChange resumed = null;
            for (int i = 0; i < 2000 && resumed == null; ++i)
            {
                lock (gate) resumed = changes.Find(c => c.State == ConnectionState.Resumed);
                if (resumed == null) Thread.Sleep(10);
            }
            lock (gate)
            {
                Check(changes.Count >= 2 && changes[0].State == ConnectionState.Lost, "Lost first: " + changes.Count + " changes");
                Check(resumed != null && resumed.NewSession && resumed.ItemsNotRestored == 0, "Resumed in a new session with every item");
            }
            if (resumed == null) return;
            Check(client.SessionId != oldSession && resumed.SessionId == client.SessionId, "the new session's id");
            var scene = client.Scene();
            Check(scene.Objects.Count == 1 && scene.Fields.Count == 1 && scene.ObjectIds[0] == wall.Id && scene.FieldIds[0] == field.Id,
                  "the wall and the field registered again, the handles on their new ids");
            client.SetOperator(OperatorInput.Push(new Vec3(0, 0, -5.0)));
            var state = StepAndGet(client, 3000);
            Near(state.Force.Z, 5.0, 1e-3, "the wall holds the push on the new server, its stream resumed");
            Check(client.ReceiveCounters.Reconnects == 1, "one reconnection counted");
            recorder.Close();
            string rows = System.IO.File.ReadAllText(recorder.EventsPath);
            Check(rows.Contains(",101,connection_lost,") && rows.Contains(",102,connection_resumed,"),
                  "the recorder's events hold the loss and the resumption: " + rows);
            // And the new server's events: its stream opened again there, in the new session.
            Check(rows.Contains(",6,watch_started," + client.SessionId + ","),
                  "the recorder watches the new session's events: " + rows);
            wall.Dispose();
            field.Dispose();
            Check(client.Scene().Objects.Count == 0, "removed on the new server");
        }
    }

    static int Main(string[] args)
    {
        if (args.Length < 1) { Console.Error.WriteLine("usage: ClientTests.exe host:port [recording-dir] | --tls host:port certs-dir | --reconnect host:port ready-file"); return 2; }
        TheAssemblyIsManagedAloneWithTheCppSdksDefaults();
        if (args[0] == "--reconnect" && args.Length == 3)
        {
            AServerRestartIsSurvivedWithEveryItem(args[1], args[2]);
            Console.WriteLine(failures == 0 ? "all C# checks passed" : failures + " C# checks failed");
            return failures == 0 ? 0 : 1;
        }
        if (args[0] == "--tls" && args.Length == 3)
        {
            TlsMutualTlsAndTokens(args[1], args[2]);
            Console.WriteLine(failures == 0 ? "all C# checks passed" : failures + " C# checks failed");
            return failures == 0 ? 0 : 1;
        }
        using (var client = new Client(new ClientConfig { ServerAddress = args[0], ClientName = "csharp-test", HeartbeatPeriodMs = 20 }))
        {
            AWallHoldsAPush(client);
            EveryKindRegistersReadsBackAndUpdates(client);
            RefusalsNameTheFieldAndChangeNothing(client);
            AScenesAppliesWholeAndReadsBack(client);
            CallbacksArriveOnAnotherThreadAndSurviveCollections(client);
            TheRestOfTheSession(client);
            if (args.Length > 1) TheRecorderWritesWhatTheClientReceived(client, args[1]);
        }
        Console.WriteLine(failures == 0 ? "all C# checks passed" : failures + " C# checks failed");
        return failures == 0 ? 0 : 1;
    }
}
