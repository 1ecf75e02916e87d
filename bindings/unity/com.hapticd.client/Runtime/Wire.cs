// The UDP data plane's datagrams in C#: the layout of proto/haptic/wire/datagram.hpp (docs/protocol.md),
// byte for byte, little-endian, each tagged with SipHash-2-4 under the session's 16-byte key. Only
// what a client needs: State and PathChallenge in, Heartbeat and PathResponse out.
//
//   header (40 bytes) | payload (fixed size per type) | tag (8 bytes)
//   0 u32 magic "HPTC" | 4 u16 version | 6 u16 type | 8 u64 session_id | 16 u64 sequence |
//   24 i64 time_ns | 32 u32 payload_size | 36 u32 reserved (0)
using System;

namespace Hapticd
{
    internal static class Wire
    {
        internal const uint Magic = 0x43545048u;  // bytes "HPTC"
        internal const ushort Version = 5;
        internal const int HeaderSize = 40;
        internal const int TagSize = 8;
        internal const ushort TypeState = 1, TypeHeartbeat = 2, TypePathChallenge = 3, TypePathResponse = 4,
            TypeStateOriented = 5;
        internal const int StatePayloadSize = 8 + 4 * 24 + 4 + 4 + 4;           // 116
        internal const int StateOrientedPayloadSize = StatePayloadSize + 32 + 24;  // 172
        internal const int HeartbeatPayloadSize = 48;
        internal const int PathPayloadSize = 16;
        internal const int MaxDatagramSize = HeaderSize + StateOrientedPayloadSize + TagSize;

        internal struct Header
        {
            internal ushort Type;
            internal ulong SessionId;
            internal ulong Sequence;
            internal long TimeNs;
        }

        /// <summary>What a client sends with each heartbeat (wire::HeartbeatPayload).</summary>
        internal struct Heartbeat
        {
            internal long ClientTimeNs;
            internal ulong LastStateSequence, StatesReceived, StatesLost;
            internal long EchoStateTimeNs, EchoHoldNs;
        }

        private static int PayloadSizeOf(ushort type)
        {
            switch (type)
            {
                case TypeState: return StatePayloadSize;
                case TypeStateOriented: return StateOrientedPayloadSize;
                case TypeHeartbeat: return HeartbeatPayloadSize;
                case TypePathChallenge:
                case TypePathResponse: return PathPayloadSize;
            }
            return 0;
        }

        // ---- little-endian fields, byte by byte (the same on any host) ----

        internal static ulong U64(byte[] b, int at)
        {
            ulong v = 0;
            for (int i = 7; i >= 0; --i) v = (v << 8) | b[at + i];
            return v;
        }
        internal static uint U32(byte[] b, int at) { return (uint)U64Part(b, at, 4); }
        internal static ushort U16(byte[] b, int at) { return (ushort)U64Part(b, at, 2); }
        internal static double F64(byte[] b, int at) { return BitConverter.Int64BitsToDouble((long)U64(b, at)); }
        private static ulong U64Part(byte[] b, int at, int bytes)
        {
            ulong v = 0;
            for (int i = bytes - 1; i >= 0; --i) v = (v << 8) | b[at + i];
            return v;
        }
        internal static void Put(byte[] b, int at, ulong v, int bytes)
        {
            for (int i = 0; i < bytes; ++i) b[at + i] = (byte)(v >> (8 * i));
        }
        private static Vec3 V(byte[] b, int at) { return new Vec3(F64(b, at), F64(b, at + 8), F64(b, at + 16)); }

        // ---- SipHash-2-4 (Aumasson & Bernstein 2012), as proto/haptic/wire/siphash.cpp ----

        private static ulong Rotl(ulong x, int b) { return (x << b) | (x >> (64 - b)); }

        internal static ulong SipHash24(byte[] key, byte[] message, int length)
        {
            ulong k0 = U64(key, 0), k1 = U64(key, 8);
            // "somepseudorandomlygeneratedbytes" in ASCII.
            ulong v0 = k0 ^ 0x736f6d6570736575UL, v1 = k1 ^ 0x646f72616e646f6dUL;
            ulong v2 = k0 ^ 0x6c7967656e657261UL, v3 = k1 ^ 0x7465646279746573UL;
            int full = length / 8 * 8;
            for (int i = 0; i <= full; i += 8)
            {
                ulong m;
                if (i < full)
                {
                    m = U64(message, i);
                }
                else
                {
                    // The last word: the remaining 0..7 bytes, the length (mod 256) in the top byte.
                    m = (ulong)(length & 0xff) << 56;
                    for (int j = full; j < length; ++j) m |= (ulong)message[j] << (8 * (j - full));
                }
                v3 ^= m;
                for (int r = 0; r < 2; ++r) Round(ref v0, ref v1, ref v2, ref v3);
                v0 ^= m;
            }
            v2 ^= 0xff;
            for (int r = 0; r < 4; ++r) Round(ref v0, ref v1, ref v2, ref v3);
            return v0 ^ v1 ^ v2 ^ v3;
        }

        private static void Round(ref ulong v0, ref ulong v1, ref ulong v2, ref ulong v3)
        {
            v0 += v1; v1 = Rotl(v1, 13); v1 ^= v0; v0 = Rotl(v0, 32);
            v2 += v3; v3 = Rotl(v3, 16); v3 ^= v2;
            v0 += v3; v3 = Rotl(v3, 21); v3 ^= v0;
            v2 += v1; v1 = Rotl(v1, 17); v1 ^= v2; v2 = Rotl(v2, 32);
        }

        // ---- decoding ----

        /// <summary>Checks the header (magic, version, type, exact length, reserved) without the
        /// tag; false for anything malformed.</summary>
        internal static bool PeekHeader(byte[] d, int length, out Header header)
        {
            header = new Header();
            if (length < HeaderSize + TagSize) return false;
            if (U32(d, 0) != Magic || U16(d, 4) != Version) return false;
            ushort type = U16(d, 6);
            int payload = PayloadSizeOf(type);
            if (payload == 0 || U32(d, 32) != payload || U32(d, 36) != 0 || length != HeaderSize + payload + TagSize) return false;
            header.Type = type;
            header.SessionId = U64(d, 8);
            header.Sequence = U64(d, 16);
            header.TimeNs = (long)U64(d, 24);
            return true;
        }

        /// <summary>Whether the tag matches (one comparison of the whole word: no early exit).</summary>
        internal static bool TagMatches(byte[] d, int length, byte[] key)
        {
            int body = length - TagSize;
            return (SipHash24(key, d, body) ^ U64(d, body)) == 0;
        }

        /// <summary>A State or StateOriented datagram as a State (tick, pose, force, ...); false if
        /// it is malformed, of another type, or its tag does not match.</summary>
        internal static bool DecodeState(byte[] d, int length, byte[] key, out Header header, out State state)
        {
            state = new State();
            if (!PeekHeader(d, length, out header) || (header.Type != TypeState && header.Type != TypeStateOriented) ||
                !TagMatches(d, length, key))
            {
                return false;
            }
            int p = HeaderSize;
            state.Tick = U64(d, p);
            state.Sequence = header.Sequence;
            state.ServerTime = header.TimeNs * 1e-9;
            state.Position = V(d, p + 8);
            state.Velocity = V(d, p + 32);
            state.Force = V(d, p + 56);
            state.Proxy = V(d, p + 80);
            state.ContactCount = U32(d, p + 104);
            state.Flags = (StateFlags)U32(d, p + 108);
            state.Buttons = U32(d, p + 112);
            state.Orientation = Quaternion.Identity;
            if (header.Type == TypeStateOriented)
            {
                state.HasOrientation = true;
                state.Orientation = new Quaternion(F64(d, p + 116), F64(d, p + 124), F64(d, p + 132), F64(d, p + 140));
                state.Torque = V(d, p + 148);
            }
            return true;
        }

        /// <summary>A PathChallenge's nonce; false unless it is one, whole and tagged.</summary>
        internal static bool DecodePathChallenge(byte[] d, int length, byte[] key, out Header header, out ulong nonce)
        {
            nonce = 0;
            if (!PeekHeader(d, length, out header) || header.Type != TypePathChallenge || !TagMatches(d, length, key)) return false;
            nonce = U64(d, HeaderSize);
            return true;
        }

        // ---- encoding ----

        private static int Encode(Header header, ushort type, int payloadSize, byte[] key, byte[] out_)
        {
            Put(out_, 0, Magic, 4);
            Put(out_, 4, Version, 2);
            Put(out_, 6, type, 2);
            Put(out_, 8, header.SessionId, 8);
            Put(out_, 16, header.Sequence, 8);
            Put(out_, 24, (ulong)header.TimeNs, 8);
            Put(out_, 32, (ulong)payloadSize, 4);
            Put(out_, 36, 0, 4);
            int body = HeaderSize + payloadSize;
            Put(out_, body, SipHash24(key, out_, body), 8);
            return body + TagSize;
        }

        /// <summary>Writes a Heartbeat datagram into out_ (at least 96 bytes); returns its size.</summary>
        internal static int EncodeHeartbeat(Header header, Heartbeat h, byte[] key, byte[] out_)
        {
            int p = HeaderSize;
            Put(out_, p, (ulong)h.ClientTimeNs, 8);
            Put(out_, p + 8, h.LastStateSequence, 8);
            Put(out_, p + 16, h.StatesReceived, 8);
            Put(out_, p + 24, h.StatesLost, 8);
            Put(out_, p + 32, (ulong)h.EchoStateTimeNs, 8);
            Put(out_, p + 40, (ulong)h.EchoHoldNs, 8);
            return Encode(header, TypeHeartbeat, HeartbeatPayloadSize, key, out_);
        }

        /// <summary>Writes a PathResponse echoing `nonce`; returns its size.</summary>
        internal static int EncodePathResponse(Header header, ulong nonce, long clientTimeNs, byte[] key, byte[] out_)
        {
            Put(out_, HeaderSize, nonce, 8);
            Put(out_, HeaderSize + 8, (ulong)clientTimeNs, 8);
            return Encode(header, TypePathResponse, PathPayloadSize, key, out_);
        }
    }
}
